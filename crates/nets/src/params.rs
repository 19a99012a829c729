//! Named parameters with seeded initialisation, the AdamW optimiser, and the safetensors
//! checkpoint format: the building blocks of envfield-nets's networks, public so that other
//! crates (envfield-vae) follow the same conventions (seeded weights, moments in checkpoints,
//! configs in file metadata, shapes checked on load).

use crate::{NetsError, Result};
use candle_core::{Device, Tensor, Var};
use envfield_grid::SplitMix64;
use safetensors::tensor::{Dtype, SafeTensors, TensorView};
use std::collections::HashMap;
use std::path::Path;

/// The most parameters a network may have (512 MB of f32): a config past it is a typo, and
/// refusing it beats an allocation that aborts.
pub const MAX_PARAMETERS: usize = 1 << 27;

/// How a parameter starts.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Init {
    /// All zeros.
    Zeros,
    /// Normal with mean 0 and this standard deviation.
    Normal(f32),
    /// Uniform in `[-bound, bound]`.
    Uniform(f32),
}

/// The trainable tensors of a network, in creation order, each with a unique name.
/// Initialisation draws from a seeded [`SplitMix64`], so a config and a seed give the same
/// network on every machine.
#[derive(Debug)]
pub struct ParamStore {
    names: Vec<String>,
    vars: Vec<Var>,
    rng: SplitMix64,
    device: Device,
}

impl ParamStore {
    /// An empty store whose initialisation draws from `seed`, on `device`.
    pub fn new(seed: u64, device: &Device) -> Self {
        Self {
            names: Vec::new(),
            vars: Vec::new(),
            rng: SplitMix64::new(seed ^ 0xE17F_1E1D),
            device: device.clone(),
        }
    }

    /// Creates the parameter `name` of `shape` and returns its tensor (which tracks gradients).
    pub fn add(&mut self, name: String, shape: &[usize], init: Init) -> Result<Tensor> {
        debug_assert!(!self.names.contains(&name), "duplicate parameter {name}");
        let n = shape
            .iter()
            .try_fold(1usize, |a, &d| a.checked_mul(d))
            .filter(|&n| n <= MAX_PARAMETERS.saturating_sub(self.count()))
            .ok_or_else(|| {
                NetsError::InvalidConfig(format!(
                    "the network would have more than {MAX_PARAMETERS} parameters (at `{name}`, \
                     shape {shape:?})"
                ))
            })?;
        let data: Vec<f32> = match init {
            Init::Zeros => vec![0.0; n],
            Init::Uniform(b) => (0..n)
                .map(|_| ((2.0 * self.rng.open_unit() - 1.0) * b as f64) as f32)
                .collect(),
            Init::Normal(std) => (0..n)
                .map(|_| (self.rng.next_normal() * std as f64) as f32)
                .collect(),
        };
        let var = Var::from_tensor(&Tensor::from_vec(data, shape, &self.device)?)?;
        let t = var.as_tensor().clone();
        self.names.push(name);
        self.vars.push(var);
        Ok(t)
    }

    /// The parameters, in creation order.
    pub fn vars(&self) -> &[Var] {
        &self.vars
    }

    /// The parameters' names, in creation order.
    pub fn names(&self) -> &[String] {
        &self.names
    }

    /// The parameters as named tensors, in creation order: what a weight file holds.
    pub fn named_tensors(&self) -> Vec<(String, Tensor)> {
        self.names
            .iter()
            .cloned()
            .zip(self.vars.iter().map(|v| v.as_tensor().clone()))
            .collect()
    }

    /// Sets every parameter from `file` (read from `path`), each checked by name and shape,
    /// and takes them out of it. Nothing is set unless every parameter is there.
    ///
    /// # Errors
    /// [`NetsError::MissingWeight`] and [`NetsError::ShapeMismatch`] naming the parameter and
    /// the file.
    pub fn load_from(&self, path: &Path, file: &mut TensorFile) -> Result<()> {
        let mut loaded = Vec::with_capacity(self.vars.len());
        for (name, var) in self.names.iter().zip(&self.vars) {
            loaded.push(file.take(path, name, var.dims(), &self.device)?);
        }
        for (var, t) in self.vars.iter().zip(loaded) {
            var.set(&t)?;
        }
        Ok(())
    }

    /// Total number of scalars.
    pub fn count(&self) -> usize {
        self.vars.iter().map(|v| v.elem_count()).sum()
    }
}

/// AdamW (decoupled weight decay) with bias correction; its moments travel in checkpoints so
/// training resumes exactly where it stopped.
#[derive(Debug)]
pub struct AdamW {
    /// The learning rate of the next step.
    pub lr: f64,
    beta1: f64,
    beta2: f64,
    eps: f64,
    weight_decay: f64,
    /// Steps taken.
    pub step: u64,
    m: Vec<Tensor>,
    v: Vec<Tensor>,
}

impl AdamW {
    /// An optimiser for `vars` at step 0, with zero moments.
    ///
    /// # Errors
    /// Tensor errors from allocating the moments.
    pub fn new(vars: &[Var], lr: f64, betas: (f64, f64), eps: f64, wd: f64) -> Result<Self> {
        let zeros = |v: &Var| v.zeros_like();
        Ok(Self {
            lr,
            beta1: betas.0,
            beta2: betas.1,
            eps,
            weight_decay: wd,
            step: 0,
            m: vars.iter().map(zeros).collect::<candle_core::Result<_>>()?,
            v: vars.iter().map(zeros).collect::<candle_core::Result<_>>()?,
        })
    }

    /// One update from the gradients of `loss`.
    pub fn backward_step(&mut self, vars: &[Var], loss: &Tensor) -> Result<()> {
        let grads = loss.backward()?;
        self.step += 1;
        let t = self.step as i32;
        let c1 = 1.0 - self.beta1.powi(t);
        let c2 = 1.0 - self.beta2.powi(t);
        let step_size = self.lr / c1;
        for (i, var) in vars.iter().enumerate() {
            let Some(g) = grads.get(var.as_tensor()) else {
                continue;
            };
            // Gradients carry the graph that made them; the moments must not, or every step's
            // graph stays alive through them.
            let g = g.detach();
            let g = &g;
            let m = ((&self.m[i] * self.beta1)? + (g * (1.0 - self.beta1))?)?;
            let v = ((&self.v[i] * self.beta2)? + (g.sqr()? * (1.0 - self.beta2))?)?;
            let denom = ((&v / c2)?.sqrt()? + self.eps)?;
            let (m, v) = (m.detach(), v.detach());
            let mut theta = var.as_tensor().detach();
            if self.weight_decay > 0.0 {
                theta = (theta * (1.0 - self.lr * self.weight_decay))?;
            }
            let update = ((&m / &denom)? * step_size)?;
            var.set(&(theta - update)?)?;
            self.m[i] = m;
            self.v[i] = v;
        }
        Ok(())
    }

    /// The moments named for a checkpoint, `m` then `v` for each of `names` (the
    /// parameters' names, in the order of the vars this optimiser was made for).
    pub fn state_tensors(&self, names: &[String]) -> Vec<(String, Tensor)> {
        let mut out = Vec::with_capacity(2 * names.len());
        for (i, name) in names.iter().enumerate() {
            out.push((moment_name('m', name), self.m[i].clone()));
            out.push((moment_name('v', name), self.v[i].clone()));
        }
        out
    }

    /// Restores moments and the step count (from [`TensorFile::take_moments`]).
    pub fn set_moments(&mut self, m: Vec<Tensor>, v: Vec<Tensor>, step: u64) {
        self.m = m;
        self.v = v;
        self.step = step;
    }
}

/// Names of optimiser tensors in checkpoints start with this.
pub const OPTIMISER_PREFIX: &str = "optimiser.";

/// The metadata key of a checkpoint's step (absent from plain weight files).
pub const META_STEP: &str = "envfield.step";

/// The checkpoint name of the moving average of parameter `name` (with the optimiser's
/// prefix, so weight loaders skip it).
pub fn ema_name(name: &str) -> String {
    format!("{OPTIMISER_PREFIX}ema.{name}")
}

fn moment_name(kind: char, name: &str) -> String {
    format!("{OPTIMISER_PREFIX}{kind}.{name}")
}

/// The metadata key of a file's format.
pub const META_FORMAT: &str = "envfield.format";
/// The format of envfield-nets's files.
pub const FORMAT: &str = "envfield-nets/1";
/// The metadata key of a file's model config (JSON).
pub const META_CONFIG: &str = "envfield.model";

/// Serialises named f32 tensors and metadata into safetensors bytes.
pub fn to_safetensors(
    tensors: &[(String, Tensor)],
    metadata: HashMap<String, String>,
) -> Result<Vec<u8>> {
    let mut bytes: Vec<(String, Vec<usize>, Vec<u8>)> = Vec::with_capacity(tensors.len());
    for (name, t) in tensors {
        let data = t.flatten_all()?.to_vec1::<f32>()?;
        let raw: Vec<u8> = data.iter().flat_map(|x| x.to_le_bytes()).collect();
        bytes.push((name.clone(), t.dims().to_vec(), raw));
    }
    let mut views = Vec::with_capacity(bytes.len());
    for (name, shape, raw) in &bytes {
        let view = TensorView::new(Dtype::F32, shape.clone(), raw)
            .map_err(|e| NetsError::InvalidInput(format!("cannot serialise tensor {name}: {e}")))?;
        views.push((name.clone(), view));
    }
    safetensors::tensor::serialize(views, Some(metadata))
        .map_err(|e| NetsError::InvalidInput(format!("cannot serialise tensors: {e}")))
}

/// The metadata of a weight file of `format` whose config is `config` (as JSON).
///
/// # Errors
/// [`NetsError::InvalidConfig`] for a config that does not serialise.
pub fn weight_metadata(
    format: &str,
    config: &impl serde::Serialize,
) -> Result<HashMap<String, String>> {
    let json = serde_json::to_string(config)
        .map_err(|e| NetsError::InvalidConfig(format!("cannot serialise the config: {e}")))?;
    Ok(HashMap::from([
        (META_FORMAT.to_string(), format.to_string()),
        (META_CONFIG.to_string(), json),
    ]))
}

/// Writes named tensors and metadata as one safetensors file, atomically (a temporary file,
/// then a rename): the one writer of every envfield weight file and checkpoint.
///
/// # Errors
/// I/O errors naming the file.
pub fn write_weights(
    path: &Path,
    tensors: &[(String, Tensor)],
    metadata: HashMap<String, String>,
) -> Result<()> {
    envfield_grid::write_atomic(path, &to_safetensors(tensors, metadata)?)?;
    Ok(())
}

/// A safetensors file read into memory: its metadata and its f32 tensors by name.
pub struct TensorFile {
    /// The file's metadata.
    pub metadata: HashMap<String, String>,
    /// Its tensors: shape and values by name.
    pub tensors: HashMap<String, (Vec<usize>, Vec<f32>)>,
}

impl TensorFile {
    /// Reads an envfield-nets file ([`FORMAT`]).
    ///
    /// # Errors
    /// [`NetsError::Checkpoint`] for an unreadable, truncated or foreign file.
    pub fn read(path: &Path) -> Result<Self> {
        Self::read_format(path, FORMAT)
    }

    /// Reads a safetensors file whose [`META_FORMAT`] metadata is `format`, with f32 tensors
    /// only.
    ///
    /// # Errors
    /// [`NetsError::Checkpoint`] for an unreadable, truncated or foreign file.
    pub fn read_format(path: &Path, format: &str) -> Result<Self> {
        let bad = |reason: String| NetsError::Checkpoint {
            path: path.to_path_buf(),
            reason,
        };
        let bytes = std::fs::read(path).map_err(|e| bad(format!("cannot read: {e}")))?;
        let (_, meta) = SafeTensors::read_metadata(&bytes)
            .map_err(|e| bad(format!("not a safetensors file or truncated ({e})")))?;
        let st = SafeTensors::deserialize(&bytes)
            .map_err(|e| bad(format!("not a safetensors file or truncated ({e})")))?;
        let metadata = meta.metadata().clone().unwrap_or_default();
        match metadata.get(META_FORMAT) {
            Some(f) if f == format => {}
            Some(f) => return Err(bad(format!("format `{f}`, expected `{format}`"))),
            None => {
                return Err(bad(format!(
                    "no `{META_FORMAT}` metadata (not written by envfield)"
                )))
            }
        }
        let mut tensors = HashMap::new();
        for (name, view) in st.tensors() {
            if view.dtype() != Dtype::F32 {
                return Err(bad(format!(
                    "tensor `{name}` is {:?}, expected F32",
                    view.dtype()
                )));
            }
            let data = view
                .data()
                .chunks_exact(4)
                .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
                .collect();
            tensors.insert(name, (view.shape().to_vec(), data));
        }
        Ok(Self { metadata, tensors })
    }

    /// Takes Adam's moments for the parameters of `store` (as written by
    /// [`AdamW::state_tensors`]), checking their shapes.
    pub fn take_moments(
        &mut self,
        path: &Path,
        store: &ParamStore,
        device: &Device,
    ) -> Result<(Vec<Tensor>, Vec<Tensor>)> {
        let (mut m, mut v) = (Vec::new(), Vec::new());
        for (name, var) in store.names().iter().zip(store.vars()) {
            m.push(self.take(path, &moment_name('m', name), var.dims(), device)?);
            v.push(self.take(path, &moment_name('v', name), var.dims(), device)?);
        }
        Ok((m, v))
    }

    /// Takes the moving average of the weights of `store` (as written by the trainer under
    /// [`ema_name`]), checking shapes. `None` when the file keeps no average, unless
    /// `required`: then a missing tensor is an error.
    pub fn take_average(
        &mut self,
        path: &Path,
        store: &ParamStore,
        device: &Device,
        required: bool,
    ) -> Result<Option<Vec<Tensor>>> {
        let names = store.names();
        if !required
            && !names
                .iter()
                .all(|n| self.tensors.contains_key(&ema_name(n)))
        {
            return Ok(None);
        }
        let take = |(n, v): (&String, &Var)| self.take(path, &ema_name(n), v.dims(), device);
        let average: Vec<Tensor> = names
            .iter()
            .zip(store.vars())
            .map(take)
            .collect::<Result<_>>()?;
        Ok(Some(average))
    }

    /// Takes tensor `name`, checking its shape.
    pub fn take(
        &mut self,
        path: &Path,
        name: &str,
        shape: &[usize],
        device: &Device,
    ) -> Result<Tensor> {
        let (found, data) = self
            .tensors
            .remove(name)
            .ok_or_else(|| NetsError::MissingWeight {
                path: path.to_path_buf(),
                name: name.to_string(),
            })?;
        if found != shape {
            return Err(NetsError::ShapeMismatch {
                path: path.to_path_buf(),
                name: name.to_string(),
                expected: shape.to_vec(),
                found,
            });
        }
        if let Some(i) = data.iter().position(|x: &f32| !x.is_finite()) {
            return Err(NetsError::Checkpoint {
                path: path.to_path_buf(),
                reason: format!("tensor `{name}` holds a non-finite value at flat index {i}"),
            });
        }
        let t = Tensor::from_vec(data, shape, device)?;
        Ok(t)
    }
}
