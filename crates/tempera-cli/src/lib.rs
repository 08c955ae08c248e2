//! The `tempera` command-line renderer's subcommands, one module each, as a library: the
//! binary (`main.rs`) parses the command line and calls them; the fuzz targets call the
//! experiment file's parser directly.

pub mod compare;
pub mod experiment;
pub mod flags;
pub mod info;
#[cfg(feature = "mpi")]
pub mod mpi;
pub mod render;
pub mod run;
pub mod scene;
pub mod stats;
