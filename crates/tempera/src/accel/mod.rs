//! Ray–scene intersection: the [`Accel`] trait, a wide BVH behind it ([`bvh::Bvh`]), Embree
//! as an alternative (feature `embree`) and a brute-force reference used to test both.

pub mod brute;
pub mod bvh;
#[cfg(feature = "embree")]
pub mod embree;
mod wide;

pub use brute::BruteForce;
pub use bvh::Bvh;

use crate::geometry::{Geometry, PrimHit, Ray};

/// Finds the nearest hit along a ray, or whether anything blocks a segment.
pub trait Accel: Send + Sync {
    /// Nearest hit with `0 < t < t_max`.
    fn intersect(&self, geometry: &Geometry, ray: &Ray, t_max: f32) -> Option<PrimHit>;
    /// True when any primitive is hit with `0 < t < t_max`.
    fn occluded(&self, geometry: &Geometry, ray: &Ray, t_max: f32) -> bool;
}

/// Which accelerator a scene is built with.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum AccelKind {
    /// Tempera's own wide BVH (the default).
    #[default]
    Bvh,
    /// Intel Embree 3 (only in builds with the `embree` feature).
    Embree,
}

impl AccelKind {
    /// Whether this build can use the accelerator.
    pub fn available(self) -> bool {
        match self {
            AccelKind::Bvh => true,
            AccelKind::Embree => cfg!(feature = "embree"),
        }
    }
}

impl std::fmt::Display for AccelKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            AccelKind::Bvh => "bvh",
            AccelKind::Embree => "embree",
        })
    }
}

/// The accelerator a scene holds.
pub enum SceneAccel {
    Bvh(Bvh),
    #[cfg(feature = "embree")]
    Embree(embree::EmbreeAccel),
}

impl SceneAccel {
    /// Builds `kind` over `geometry` (the BVH reorders its primitive table).
    pub fn build(kind: AccelKind, geometry: &mut Geometry) -> Result<Self, String> {
        match kind {
            AccelKind::Bvh => Ok(SceneAccel::Bvh(Bvh::build(geometry))),
            #[cfg(feature = "embree")]
            AccelKind::Embree => {
                geometry.ensure_triangle_cache();
                embree::EmbreeAccel::build(geometry).map(SceneAccel::Embree)
            }
            #[cfg(not(feature = "embree"))]
            AccelKind::Embree => Err("this build has no Embree (build with `--features embree`)".into()),
        }
    }

    pub fn kind(&self) -> AccelKind {
        match self {
            SceneAccel::Bvh(_) => AccelKind::Bvh,
            #[cfg(feature = "embree")]
            SceneAccel::Embree(_) => AccelKind::Embree,
        }
    }
}

impl Accel for SceneAccel {
    #[inline]
    fn intersect(&self, geometry: &Geometry, ray: &Ray, t_max: f32) -> Option<PrimHit> {
        match self {
            SceneAccel::Bvh(a) => a.intersect(geometry, ray, t_max),
            #[cfg(feature = "embree")]
            SceneAccel::Embree(a) => a.intersect(geometry, ray, t_max),
        }
    }

    #[inline]
    fn occluded(&self, geometry: &Geometry, ray: &Ray, t_max: f32) -> bool {
        match self {
            SceneAccel::Bvh(a) => a.occluded(geometry, ray, t_max),
            #[cfg(feature = "embree")]
            SceneAccel::Embree(a) => a.occluded(geometry, ray, t_max),
        }
    }
}
