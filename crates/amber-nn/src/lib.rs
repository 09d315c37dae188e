//! What AMBER's two candle networks (the message passing network in `amber-mpn`, the U-Net in
//! `amber-cnn`) share: [`Adam`] with global gradient-norm clipping whose moments can be saved and
//! restored (so a resumed run continues exactly, and benchmarks time the optimiser that trains),
//! the adapter that turns a kernel written as slice loops into a candle custom op ([`op`]), the
//! parallel reductions whose result does not depend on the thread count, so that training is
//! bit-reproducible at any number of threads ([`reduce`]), the finiteness check of a loaded
//! weights file ([`first_non_finite`]), the finite-difference gradient checker of both crates'
//! op tests ([`gradcheck`]), and the one map between a network's scalar output and an element
//! size ([`Objective`]), and the device a network trains on ([`Backend`]).
//!
//! This crate depends on candle, rayon and serde only; it knows nothing of meshes, graphs,
//! images or training loops.

mod adam;
mod backend;
mod finite;
pub mod gradcheck;
mod objective;
pub mod op;
pub mod reduce;

pub use adam::Adam;
pub use backend::Backend;
pub use finite::first_non_finite;
pub use objective::{Objective, softplus, softplus_inverse};
