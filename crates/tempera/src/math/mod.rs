//! Math foundations: glam re-exports, RGB colour, orthonormal frames, warps, random numbers and
//! piecewise-constant distributions.

pub mod distribution;
pub mod frame;
pub mod rng;
pub mod warp;

pub use glam::{Mat3, Mat4, Quat, Vec2, Vec3, Vec3A, Vec4};

/// Linear RGB radiometric quantity (sRGB / Rec. 709 primaries).
pub type Rgb = Vec3;

/// Rec. 709 luminance of a linear RGB value.
#[inline]
pub fn luminance(c: Rgb) -> f32 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

/// True when every channel is finite and non-negative.
#[inline]
pub fn is_valid_radiance(c: Rgb) -> bool {
    c.is_finite() && c.min_element() >= 0.0
}

/// Power heuristic with exponent 2 for one sample from each of two strategies (Veach 1997, §9.2.4).
#[inline]
pub fn power_heuristic(pdf_a: f32, pdf_b: f32) -> f32 {
    let a = pdf_a * pdf_a;
    let b = pdf_b * pdf_b;
    if a.is_infinite() {
        return 1.0;
    }
    if a + b == 0.0 { 0.0 } else { a / (a + b) }
}

/// Safe square root: negative arguments (from round-off) give zero.
#[inline]
pub fn safe_sqrt(x: f32) -> f32 {
    x.max(0.0).sqrt()
}

/// Mirror `w` about the normal `n` (both pointing away from the surface).
#[inline]
pub fn reflect(w: Vec3, n: Vec3) -> Vec3 {
    -w + 2.0 * w.dot(n) * n
}
