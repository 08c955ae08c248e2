//! The bidirectional path machinery shared by BDPT and every MCMC integrator: vertices with
//! their densities, subpath random walks, evaluation of one strategy at a time, and MIS.

pub mod connect;
pub mod mis;
pub mod subpath;
pub mod temper;
pub mod vertex;

#[cfg(test)]
mod tests;

pub use connect::{Connection, Subpaths, connect};
pub use mis::{Heuristic, ReversePdfs, mis_weight, mis_weight_with, reverse_pdfs};
pub use subpath::{camera_subpath, camera_subpath_vertices, light_subpath, light_subpath_vertices};
pub use temper::{TemperScratch, Tempering, tempered};
pub use vertex::{Vertex, VertexKind};

/// Storage for one camera and one light subpath, reused from sample to sample by whoever
/// evaluates samples (a tile worker, a Markov chain, a bootstrap thread).
#[derive(Clone, Debug, Default)]
pub struct Paths {
    pub camera: Vec<Vertex>,
    pub light: Vec<Vertex>,
}

impl Paths {
    /// The two subpaths, for [`connect`].
    pub fn subpaths(&self) -> Subpaths<'_> {
        Subpaths { light: &self.light, camera: &self.camera }
    }
}
