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
//! - [`TargetEncoding`]: the one owner of how distances become outputs and back (the paper's
//!   `1/(1+d)`, or `1 - d/scale`); datasets store distances, networks encode them.
//! - [`Trainer`]: L1 on the network's encoding plus optional neighbour-difference and descent
//!   losses, AdamW, seeded batches from [`envfield_mazes::Dataset`]s, atomic safetensors
//!   checkpoints that resume exactly and refuse other data ([`Trainer::continue_with_data`]).
//!   [`Arch::preset`] gives the networks the examples train.
//! - [`Vin`]: the Value Iteration Network baseline (Tamar et al. 2016), trained by imitation
//!   ([`VinTrainer`]); it is a [`Policy`](envfield_grid::Policy), which
//!   `envfield_plan::PolicyWalk` plans with, one network pass per step.
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

mod batch;
mod config;
mod encoding;
mod error;
mod files;
mod kernel;
mod layers;
mod net;
pub mod params;
mod train;
mod vin;

pub use batch::Batch;
pub use config::{
    parse_convs, Arch, ContextConfig, GoalConfig, HyperConfig, ModelConfig, PathConfig,
    PlainConfig, PropagationConfig,
};
pub use encoding::{TargetEncoding, BLOCKED};
pub use envfield_grid::FieldModel;
pub use error::{NetsError, Result};
pub use files::model_file;
pub use layers::{Activation, ConvSpec, MlpConfig};
pub use net::{BoundField, FieldNet, MAX_FIELD_CELLS};
pub use train::{
    resume_on, validation_loss, ContextOptions, DataCheck, LossShaping, MazeRecipe, Progress,
    TrainConfig, TrainSummary, Trainer,
};
pub use vin::{Vin, VinConfig, VinData, VinStep, VinTrainConfig, VinTrainer};
