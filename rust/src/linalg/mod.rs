//! Linear algebra: the sparse LDLᵀ of the stepping matrices (`sparse`, on faer's supernodal
//! symbolic analysis), the block-tridiagonal factor of meshes that share their nodes
//! (`banded`), small dense systems through faer (`dense`) and the lane-wise SIMD kernels of
//! lockstep batches (`simd`).

pub mod banded;
pub mod dense;
pub mod simd;
pub mod sparse;
