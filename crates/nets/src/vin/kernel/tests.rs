//! The hand-written passes against candle's, and their gradients against finite differences.
use super::*;
use candle_core::{Device, Tensor, Var, D};

/// A random map, goal and weights large enough that the max has no ties.
fn case(
    rows: usize,
    cols: usize,
    hidden: usize,
    qc: usize,
    seed: u64,
) -> (Vec<bool>, usize, Weights) {
    let mut rng = envfield_grid::SplitMix64::new(seed);
    let obstacles: Vec<bool> = (0..rows * cols).map(|_| rng.below(4) == 0).collect();
    let goal = (0..rows * cols).find(|&p| !obstacles[p]).unwrap_or(0);
    let mut normal =
        |n: usize, s: f32| -> Vec<f32> { (0..n).map(|_| s * rng.next_normal() as f32).collect() };
    let wt = Weights {
        h_w: normal(18 * hidden, 0.3),
        h_b: normal(hidden, 0.1),
        r_w: normal(hidden, 0.3),
        r_b: normal(1, 0.1),
        q_w: normal(18 * qc, 0.3),
        q_b: normal(qc, 0.1),
        p_w: normal(qc * ACTIONS, 0.3),
        p_b: normal(ACTIONS, 0.1),
    };
    (obstacles, goal, wt)
}

/// The same network and loss in candle's ops (NCHW convolutions, its autograd), for the
/// gradient of every weight.
fn candle_loss_and_grad(
    wt: &Weights,
    obstacles: &[bool],
    (rows, cols, goal): (usize, usize, usize),
    iterations: usize,
    states: &[(usize, u8)],
) -> (f32, Weights) {
    let dev = Device::Cpu;
    let (hidden, qc) = (wt.hidden(), wt.q_channels());
    let vars: Vec<Var> = wt
        .parts()
        .iter()
        .map(|p| Var::from_vec(p.to_vec(), p.len(), &dev).unwrap())
        .collect();
    let v = |i: usize| vars[i].as_tensor();
    // The flat weights reshaped in the graph, so gradients come back flat.
    let hk = {
        let w = v(0).reshape((9, 2, hidden)).unwrap();
        w.permute((2, 1, 0))
            .unwrap()
            .reshape((hidden, 2, 3, 3))
            .unwrap()
    };
    let qk = |ch: usize| {
        let w = v(4).reshape((9, 2, qc)).unwrap().narrow(1, ch, 1).unwrap();
        w.permute((2, 1, 0))
            .unwrap()
            .reshape((qc, 1, 3, 3))
            .unwrap()
    };
    let mut x = vec![0f32; 2 * rows * cols];
    for (p, &o) in obstacles.iter().enumerate() {
        x[p] = f32::from(u8::from(o));
    }
    x[rows * cols + goal] = GOAL_REWARD;
    let x = Tensor::from_vec(x, (1, 2, rows, cols), &dev).unwrap();
    let h = x
        .conv2d(&hk, 1, 1, 1, 1)
        .unwrap()
        .broadcast_add(&v(1).reshape((1, hidden, 1, 1)).unwrap())
        .unwrap();
    let r = h
        .permute((0, 2, 3, 1))
        .unwrap()
        .reshape((rows * cols, hidden))
        .unwrap()
        .matmul(&v(2).reshape((hidden, 1)).unwrap())
        .unwrap()
        .broadcast_add(v(3))
        .unwrap()
        .reshape((1, 1, rows, cols))
        .unwrap();
    let base = r
        .conv2d(&qk(0), 1, 1, 1, 1)
        .unwrap()
        .broadcast_add(&v(5).reshape((1, qc, 1, 1)).unwrap())
        .unwrap();
    let mut q = base.clone();
    for _ in 0..iterations {
        let value = q.max_keepdim(1).unwrap();
        q = (&base + value.conv2d(&qk(1), 1, 1, 1, 1).unwrap()).unwrap();
    }
    let flat = q.reshape((qc, rows * cols)).unwrap().t().unwrap();
    let ids: Vec<u32> = states.iter().map(|s| s.0 as u32).collect();
    let ids = Tensor::from_vec(ids, states.len(), &dev).unwrap();
    let at = flat.contiguous().unwrap().index_select(&ids, 0).unwrap();
    let z = at
        .matmul(&v(6).reshape((qc, ACTIONS)).unwrap())
        .unwrap()
        .broadcast_add(v(7))
        .unwrap();
    let labels: Vec<u32> = states.iter().map(|s| u32::from(s.1)).collect();
    let labels = Tensor::from_vec(labels, states.len(), &dev).unwrap();
    let logp = candle_nn::ops::log_softmax(&z, D::Minus1).unwrap();
    let picked = logp.gather(&labels.unsqueeze(1).unwrap(), 1).unwrap();
    let loss = picked.sum_all().unwrap().neg().unwrap();
    let grads = loss.backward().unwrap();
    let parts = vars
        .iter()
        .map(|var| grads.get(var).unwrap().to_vec1::<f32>().unwrap())
        .collect();
    (loss.to_scalar::<f32>().unwrap(), Weights::from_parts(parts))
}

fn close(a: &[f32], b: &[f32], what: &str) {
    let scale = b.iter().fold(1e-3f32, |m, x| m.max(x.abs()));
    for (i, (x, y)) in a.iter().zip(b).enumerate() {
        assert!(
            (x - y).abs() <= 2e-3 * scale,
            "{what}[{i}]: kernel {x}, candle {y} (scale {scale})"
        );
    }
}

#[test]
fn forward_and_backward_match_candles_autograd() {
    for (rows, cols, k, seed) in [(5, 7, 4, 1), (8, 8, 10, 2), (6, 4, 0, 3)] {
        let (obstacles, goal, wt) = case(rows, cols, 6, 4, seed);
        let free: Vec<usize> = (0..rows * cols).filter(|&p| !obstacles[p]).collect();
        let states: Vec<(usize, u8)> = (0..5)
            .map(|i| (free[(i * 7) % free.len()], (i * 3 % 8) as u8))
            .collect();
        let map = MapInput {
            obstacles: &obstacles,
            rows,
            cols,
            goal,
        };
        let fwd = forward(&wt, map, k, true);
        let mut grad = wt.zeros_like();
        let loss = backward(&wt, &fwd, &states, &mut grad);
        let (want, want_grad) =
            candle_loss_and_grad(&wt, &obstacles, (rows, cols, goal), k, &states);
        assert!(
            (loss - want).abs() <= 1e-3 * want.abs().max(1.0),
            "loss {loss} vs {want}"
        );
        let names = ["h.w", "h.b", "r.w", "r.b", "q.w", "q.b", "p.w", "p.b"];
        for ((a, b), name) in grad.parts().iter().zip(want_grad.parts()).zip(names) {
            close(a, b, name);
        }
    }
}

#[test]
fn backward_matches_finite_differences() {
    let (rows, cols) = (6, 6);
    let (obstacles, goal, wt) = case(rows, cols, 3, 3, 9);
    let map = MapInput {
        obstacles: &obstacles,
        rows,
        cols,
        goal,
    };
    let states = [(7usize, 2u8), (20, 5), (33, 0)];
    let loss_of = |w: &Weights| {
        let fwd = forward(w, map, 5, true);
        backward(w, &fwd, &states, &mut w.zeros_like()) as f64
    };
    let mut grad = wt.zeros_like();
    backward(&wt, &forward(&wt, map, 5, true), &states, &mut grad);
    let eps = 3e-3f32;
    for part in 0..8 {
        for i in [0, wt.parts()[part].len() - 1] {
            let mut plus = wt.clone();
            plus.parts_mut()[part][i] += eps;
            let mut minus = wt.clone();
            minus.parts_mut()[part][i] -= eps;
            let fd = (loss_of(&plus) - loss_of(&minus)) / (2.0 * f64::from(eps));
            let g = f64::from(grad.parts()[part][i]);
            assert!(
                (fd - g).abs() <= 0.05 * g.abs().max(0.05),
                "part {part} index {i}: finite difference {fd}, backward {g}"
            );
        }
    }
}
