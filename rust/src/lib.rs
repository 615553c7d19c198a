//! vtb — vehicle–track–bridge vertical dynamics.
//!
//! The core library, by trade, each folder importing only from those below it:
//!
//! - `config`: the configuration schema (serde, JSON, the fields' own checks): a leaf;
//! - `linalg`: sparse, banded and dense linear algebra, the lane-wise SIMD kernels;
//! - `model`: the physics assembled from a configuration — bases, layers, couplings, the
//!   structure, the FE–SEA correction, dampers, contact, vehicles, the resolved band;
//! - `outputs`: a run's records, the index catalogue, bands, the band-limiting filter, comfort;
//! - `check`: the one judge of a configuration — every validation phase, plausibility, the
//!   memory budget — above the model and the outputs;
//! - `engine`: the runs — the entrance (batches and lockstep groups), the coupled loop the
//!   engines share, Newmark and the complex-modal synthesis;
//! - `library`: the presets and the train library.
//!
//! It has no Python types; the `vtb._core` extension module in `rust/bindings` wraps it.
//!
//! ```no_run
//! use vtb::{Config, Profile, simulate};
//! let cfg = Config::from_json(&std::fs::read_to_string("config.json").unwrap()).unwrap();
//! let result = simulate(&cfg, &Profile::flat(), None).unwrap();
//! println!("{:?}", result.metrics());
//! ```

// `!(x > 0.0)` also refuses NaN: the validation's idiom, kept over `partial_cmp`.
#![allow(clippy::neg_cmp_op_on_partial_ord)]
// The numeric kernels walk several arrays with one index; iterator chains would hide that.
#![allow(clippy::needless_range_loop)]

pub mod check;
pub mod config;
pub mod engine;
pub mod error;
pub mod library;
pub mod linalg;
pub mod model;
pub mod outputs;

/// The results epoch: raised by every change that alters a run's results (a model, a
/// solver, an index's definition), and only then. Study journals and optimiser checkpoints
/// carry it, and a resume across two epochs is refused rather than mixing their rows; a
/// change of the vtb version alone does not refuse one. `tests/test_results_epoch.py` holds
/// a fingerprint of a few runs' indices that fails until the epoch is raised.
pub const RESULTS_EPOCH: u32 = 2;

pub use config::{Config, Profile};
pub use engine::{
    BatchOptions, Control, Job, Reduced, Sink, run_batch, run_batch_each, run_batch_with, simulate,
    simulate_with,
};
pub use error::{Result, VtbError};
pub use model::Model;
pub use outputs::{Record, RunResult};
