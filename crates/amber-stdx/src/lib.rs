//! The small helpers every crate of the workspace needs once (rust-analyzer's `stdx` habit):
//! files that appear atomically and survive a crash ([`write_atomic`] and its variants: a
//! temporary file beside the target, fsynced, renamed, the directory fsynced), JSON files read
//! and written with errors that name the file ([`read_json`], [`write_json_atomic`]), the
//! quantile and median of a sample ([`quantile`], [`median`]), and items grouped by a small
//! integer key in linear time, the compressed rows of every adjacency table ([`Buckets`]). It
//! depends on no crate of ours and knows nothing of meshes, sizing fields, FEM, graphs, learning
//! or experiments; every crate may depend on it, and each maps [`FileError`] into its own error
//! type.

mod buckets;
mod fs;
mod stats;

pub use buckets::{Buckets, offsets_of};
pub use fs::{
    FileError, read_json, remove_stale_temporaries, write_atomic, write_atomic_via, write_atomic_with,
    write_json_atomic,
};
pub use stats::{median, quantile};
