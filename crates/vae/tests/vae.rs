//! The VAE, its training and files: behaviour checked against known answers, and bad input
//! refused with a clear error. Trained on rooms, it is tested in envfield-rooms.

use envfield_vae::{
    Cvae, PoseKind, RoomTorsos, SampleOptions, TorsoSource, VaeConfig, VaeError, VaeKind,
    VaeTrainConfig, VaeTrainer,
};

fn small() -> VaeConfig {
    VaeConfig {
        pointnet: vec![16, 32],
        points: 64,
        latent: 4,
        hidden: 32,
        layers: 2,
        ..VaeConfig::default()
    }
}

fn tmp(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("envfield-vae-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn cloud(n: usize, seed: u64) -> Vec<[f32; 3]> {
    let mut rng = envfield_grid::SplitMix64::new(seed);
    (0..n)
        .map(|_| {
            [
                5.0 * rng.next_f32(),
                4.0 * rng.next_f32(),
                2.0 * rng.next_f32(),
            ]
        })
        .collect()
}

/// The scene feature, and so every sample, does not depend on the order of the points.
#[test]
fn the_scene_feature_ignores_point_order() {
    let vae = Cvae::new(small(), 3).unwrap();
    let points = cloud(200, 1);
    let mut reversed = points.clone();
    reversed.reverse();
    reversed.rotate_left(37);
    let a = vae
        .as_whole()
        .unwrap()
        .scene_feature(&points)
        .unwrap()
        .flatten_all()
        .unwrap()
        .to_vec1::<f32>()
        .unwrap();
    let b = vae
        .as_whole()
        .unwrap()
        .scene_feature(&reversed)
        .unwrap()
        .flatten_all()
        .unwrap()
        .to_vec1::<f32>()
        .unwrap();
    assert_eq!(a, b);
    assert_eq!(
        vae.sample(&points, &SampleOptions::new(10, 4)).unwrap(),
        vae.sample(&reversed, &SampleOptions::new(10, 4)).unwrap()
    );
    // Another cloud gives another feature.
    let c = vae
        .as_whole()
        .unwrap()
        .scene_feature(&cloud(200, 2))
        .unwrap()
        .flatten_all()
        .unwrap()
        .to_vec1::<f32>()
        .unwrap();
    assert_ne!(a, c);
}

/// The encoder gives one Gaussian per torso; the same seed gives the same samples.
#[test]
fn encode_decode_and_sample_have_their_shapes_and_are_seeded() {
    let vae = Cvae::new(small(), 0).unwrap();
    let points = cloud(64, 5);
    let (mean, log_var) = vae
        .as_whole()
        .unwrap()
        .encode(&points, &[[1.0, 1.0, 1.0], [2.0, 1.0, 0.5]])
        .unwrap();
    assert_eq!(mean.dims(), &[2, 4]);
    assert_eq!(log_var.dims(), &[2, 4]);
    let z = candle_core::Tensor::zeros((3, 4), candle_core::DType::F32, &candle_core::Device::Cpu)
        .unwrap();
    assert_eq!(
        vae.as_whole().unwrap().decode(&points, &z).unwrap().len(),
        3
    );
    assert_eq!(vae.kind(), VaeKind::Whole);
    assert!(vae.as_local().is_none() && vae.as_gated().is_none());
    assert_eq!(
        vae.sample(&points, &SampleOptions::new(7, 9)).unwrap(),
        vae.sample(&points, &SampleOptions::new(7, 9)).unwrap()
    );
    assert_ne!(
        vae.sample(&points, &SampleOptions::new(7, 9)).unwrap(),
        vae.sample(&points, &SampleOptions::new(7, 10)).unwrap()
    );
}

/// A lower sampling temperature draws closer together; temperature 1 is `sample`; a
/// temperature outside (0, 10] is refused.
#[test]
fn tempered_samples_spread_with_the_temperature() {
    let vae = Cvae::new(small(), 0).unwrap();
    let points = cloud(64, 5);
    assert_eq!(
        vae.sample(&points, &SampleOptions::new(50, 9).with_temperature(1.0))
            .unwrap(),
        vae.sample(&points, &SampleOptions::new(50, 9)).unwrap()
    );
    let spread = |t: f32| {
        let s = vae
            .sample(&points, &SampleOptions::new(400, 9).with_temperature(t))
            .unwrap();
        let mean: [f32; 3] = std::array::from_fn(|a| s.iter().map(|p| p[a]).sum::<f32>() / 400.0);
        s.iter()
            .map(|p| (0..3).map(|a| (p[a] - mean[a]).powi(2)).sum::<f32>())
            .sum::<f32>()
            / 400.0
    };
    assert!(
        spread(0.1) < 0.5 * spread(2.0),
        "{} {}",
        spread(0.1),
        spread(2.0)
    );
    for t in [0.0, -1.0, f32::NAN, 11.0] {
        let e = vae
            .sample(&points, &SampleOptions::new(5, 9).with_temperature(t))
            .unwrap_err()
            .to_string();
        assert!(e.contains("temperature"), "{e}");
    }
}

/// Bad input is refused with an error naming it: an empty cloud, NaN coordinates, a code of
/// the wrong width, no samples, a bad config.
#[test]
fn bad_input_is_refused() {
    let vae = Cvae::new(small(), 0).unwrap();
    let err = |r: Result<Vec<[f32; 3]>, VaeError>| r.unwrap_err().to_string();
    assert!(err(vae.sample(&[], &SampleOptions::new(3, 0))).contains("no points"));
    let mut bad = cloud(10, 1);
    bad[4][1] = f32::NAN;
    assert!(err(vae.sample(&bad, &SampleOptions::new(3, 0))).contains("point 4"));
    assert!(vae
        .as_whole()
        .unwrap()
        .encode(&cloud(10, 1), &[[0.0, f32::INFINITY, 0.0]])
        .is_err());
    let z = candle_core::Tensor::zeros((3, 5), candle_core::DType::F32, &candle_core::Device::Cpu)
        .unwrap();
    assert!(vae.as_whole().unwrap().decode(&cloud(10, 1), &z).is_err());
    assert!(err(vae.sample(&cloud(10, 1), &SampleOptions::new(0, 0))).contains("samples"));
    let config = VaeConfig {
        latent: 0,
        ..small()
    };
    assert!(
        matches!(Cvae::new(config, 0), Err(VaeError::InvalidConfig(m)) if m.contains("latent"))
    );
}

/// A saved VAE loads with the same weights; a file of another kind is refused and names
/// itself.
#[test]
fn files_round_trip_and_other_files_are_refused() {
    let vae = Cvae::new(small(), 8).unwrap();
    let path = tmp("vae.safetensors");
    vae.save(&path).unwrap();
    let loaded = Cvae::load(&path).unwrap();
    let points = cloud(64, 2);
    assert_eq!(
        vae.sample(&points, &SampleOptions::new(5, 1)).unwrap(),
        loaded.sample(&points, &SampleOptions::new(5, 1)).unwrap()
    );
    // A field network's file: another format.
    let net = envfield_nets::FieldNet::new(
        envfield_nets::ModelConfig::Context(envfield_nets::ContextConfig::default()),
        0,
    )
    .unwrap();
    let other = tmp("field.safetensors");
    net.save(&other).unwrap();
    let e = Cvae::load(&other).unwrap_err().to_string();
    assert!(
        e.contains("envfield-vae/1") && e.contains("field.safetensors"),
        "{e}"
    );
    // A weight file is not a checkpoint.
    assert!(VaeTrainer::resume(&path)
        .unwrap_err()
        .to_string()
        .contains("not a training checkpoint"));
    // A truncated file.
    let bytes = std::fs::read(&path).unwrap();
    std::fs::write(&path, &bytes[..bytes.len() / 2]).unwrap();
    assert!(Cvae::load(&path).is_err());
}

/// Training lowers the loss, and a run stopped and resumed from its checkpoint ends with the
/// same weights as one that never stopped.
#[test]
fn training_resumes_exactly() {
    // Torsos standing 0.9 m above a 5 x 4 m floor of the cloud.
    let mut rng = envfield_grid::SplitMix64::new(3);
    let torsos: Vec<[f32; 3]> = (0..200)
        .map(|_| [5.0 * rng.next_f32(), 4.0 * rng.next_f32(), 0.9])
        .collect();
    let data = vec![RoomTorsos {
        cloud: cloud(256, 3),
        sources: vec![TorsoSource::Stand; torsos.len()],
        kinds: vec![Some(PoseKind::Standing); torsos.len()],
        torsos,
    }];
    let config = VaeTrainConfig {
        lr: 1e-3,
        steps: 40,
        scenes_per_step: 2,
        torsos_per_scene: 16,
        checkpoint_every: 0,
        ..VaeTrainConfig::default()
    };
    let mut whole = VaeTrainer::new(Cvae::new(small(), 1).unwrap(), config.clone()).unwrap();
    let mut losses = Vec::new();
    whole
        .run(&data, None, |p| {
            losses.push(p.recon);
            true
        })
        .unwrap();
    assert!(
        losses[35..].iter().sum::<f32>() < losses[..5].iter().sum::<f32>(),
        "{losses:?}"
    );
    let ckpt = tmp("vae.ckpt");
    let mut first = VaeTrainer::new(Cvae::new(small(), 1).unwrap(), config).unwrap();
    first.run(&data, Some(&ckpt), |p| p.step < 17).unwrap();
    let mut resumed = VaeTrainer::resume(&ckpt).unwrap();
    assert_eq!(resumed.step(), 17);
    resumed.run(&data, None, |_| true).unwrap();
    let points = cloud(64, 4);
    assert_eq!(
        whole
            .vae()
            .sample(&points, &SampleOptions::new(6, 2))
            .unwrap(),
        resumed
            .vae()
            .sample(&points, &SampleOptions::new(6, 2))
            .unwrap()
    );
    assert!(
        VaeTrainer::new(Cvae::new(small(), 1).unwrap(), whole.config().clone())
            .unwrap()
            .run(&[], None, |_| true)
            .is_err()
    );
}
