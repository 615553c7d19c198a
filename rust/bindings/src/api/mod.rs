//! The functions and classes of `vtb._core`, by what they serve.

pub(crate) mod config;
pub(crate) mod run;
pub(crate) mod signal;
pub(crate) mod structure;
