//! Implicit environment-field networks (paper sections 3.2 and 3.4, appendix A.1 and A.4) on
//! [candle](https://github.com/huggingface/candle), their training and their checkpoints.
//!
//! - [`FieldNet`]: one type for the four architectures of [`ModelConfig`]: a plain field
//!   (query -> distance), a goal-conditioned field (goal, query -> distance, 2D or 3D), the
//!   context-aligned implicit function (a fully convolutional maze encoder sampled at the
//!   query, then an MLP), and a hypernetwork that predicts the weights of a SIREN. ReLU or
//!   sine activations ([`Activation`]), positional encodings ([`MlpConfig::fourier`]).
//! - A whole field in one batched pass ([`FieldNet::field`], also [`FieldModel::predict`]) and
//!   gradients with respect to the query ([`FieldNet::predict_with_gradient`],
//!   [`BoundField`], a [`ContinuousField2`](envfield_grid::ContinuousField2)).
//! - [`Trainer`]: L1 on the paper's encoding, AdamW, seeded batches from
//!   [`envfield_mazes::Dataset`]s, atomic safetensors checkpoints that resume exactly.
//! - [`Vin`]: the Value Iteration Network baseline (Tamar et al. 2016), trained by imitation
//!   ([`VinTrainer`]), and a [`Planner`](envfield_plan::Planner) that runs it at every step.
//! - Weight files carry their config: [`FieldNet::load`] rebuilds the network, checking every
//!   tensor's name and shape; [`model_file`] picks a family's file for a maze size.
//!
//! Convolutions run channels-last as a gather (im2col) and one matrix multiply, which on a
//! CPU is several times faster than candle's direct convolution, forward and backward.
//!
//! ```
//! use envfield_grid::{Cell2, FieldModel, Grid2};
//! use envfield_nets::{ContextConfig, FieldNet, ModelConfig};
//!
//! let net = FieldNet::new(ModelConfig::Context(ContextConfig::default()), 7)?;
//! let grid = Grid2::new(8, 8)?;
//! let field = net.predict(&grid, Cell2::new(3, 4))?; // untrained, but any size works
//! assert_eq!(field.values().len(), 64);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod error;
mod files;
mod kernel;
mod layers;
mod model;
mod params;
mod train;
mod vin;

pub use envfield_grid::FieldModel;
pub use error::{NetsError, Result};
pub use files::model_file;
pub use layers::{Activation, ConvSpec, MlpConfig};
pub use model::{
    prediction_to_distance, Batch, BoundField, ContextConfig, FieldNet, GoalConfig, HyperConfig,
    ModelConfig, PlainConfig, PropagationConfig, TargetEncoding,
};
pub use train::{validation_loss, Progress, TrainConfig, TrainSummary, Trainer};
pub use vin::{vin_examples, Vin, VinConfig, VinExample, VinTrainConfig, VinTrainer};
