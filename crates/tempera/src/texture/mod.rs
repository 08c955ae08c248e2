//! Textures: constant, bilinear image, 2D checkerboard and the product of two textures
//! (pbrt-v4 §10.4). Float textures are RGB textures read through their first channel.

pub mod image;

pub use image::{Image, ImageTexture, WrapMode};

use crate::math::{Rgb, Vec2};

/// Affine uv mapping `(u·su + du, v·sv + dv)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UvMapping {
    pub su: f32,
    pub sv: f32,
    pub du: f32,
    pub dv: f32,
}

impl Default for UvMapping {
    fn default() -> Self {
        Self { su: 1.0, sv: 1.0, du: 0.0, dv: 0.0 }
    }
}

impl UvMapping {
    #[inline]
    pub fn map(&self, uv: Vec2) -> Vec2 {
        Vec2::new(uv.x * self.su + self.du, uv.y * self.sv + self.dv)
    }
}

/// A 2D checkerboard alternating between two textures on unit squares of mapped uv.
#[derive(Clone, Debug)]
pub struct Checkerboard {
    pub even: Texture,
    pub odd: Texture,
    pub mapping: UvMapping,
}

/// A texture: what shading reads at a surface point.
#[derive(Clone, Debug)]
pub enum Texture {
    Constant(Rgb),
    Image(ImageTexture),
    Checkerboard(Box<Checkerboard>),
    Scale(Box<(Texture, Texture)>),
    /// `(1 - amount)·a + amount·b` for `(a, b, amount)`.
    Mix(Box<(Texture, Texture, Texture)>),
}

impl From<Rgb> for Texture {
    fn from(c: Rgb) -> Self {
        Texture::Constant(c)
    }
}

impl From<f32> for Texture {
    fn from(v: f32) -> Self {
        Texture::Constant(Rgb::splat(v))
    }
}

impl Texture {
    /// The value at texture coordinates `uv`.
    #[inline]
    pub fn eval(&self, uv: Vec2) -> Rgb {
        match self {
            Texture::Constant(c) => *c,
            Texture::Image(t) => t.bilinear(uv),
            Texture::Checkerboard(c) => {
                let st = c.mapping.map(uv);
                if (st.x.floor() as i64 + st.y.floor() as i64) % 2 == 0 { c.even.eval(uv) } else { c.odd.eval(uv) }
            }
            Texture::Scale(pair) => pair.0.eval(uv) * pair.1.eval(uv),
            Texture::Mix(m) => {
                let t = m.2.eval_float(uv);
                (1.0 - t) * m.0.eval(uv) + t * m.1.eval(uv)
            }
        }
    }

    /// The value of a float texture.
    #[inline]
    pub fn eval_float(&self, uv: Vec2) -> f32 {
        self.eval(uv).x
    }

    /// Average over texture space (exact for constant, image and checkerboard; the product of
    /// the averages for a scale texture). Used to estimate emitted power.
    pub fn average(&self) -> Rgb {
        match self {
            Texture::Constant(c) => *c,
            Texture::Image(t) => {
                let m = t.image.mean() * t.scale;
                if t.invert { (Rgb::ONE - m).max(Rgb::ZERO) } else { m }
            }
            Texture::Checkerboard(c) => 0.5 * (c.even.average() + c.odd.average()),
            Texture::Scale(pair) => pair.0.average() * pair.1.average(),
            Texture::Mix(m) => {
                let t = m.2.average().x;
                (1.0 - t) * m.0.average() + t * m.1.average()
            }
        }
    }

    /// The constant value, when the texture is constant.
    pub fn as_constant(&self) -> Option<Rgb> {
        match self {
            Texture::Constant(c) => Some(*c),
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Arc;

    fn ramp() -> ImageTexture {
        // 2×2 image: top row (v near 1) 0 and 1, bottom row 2 and 3.
        let px = [0.0, 1.0, 2.0, 3.0].map(Rgb::splat).to_vec();
        ImageTexture::new(Arc::new(Image::new(2, 2, px)))
    }

    #[test]
    fn bilinear_hits_texel_centres_and_interpolates() {
        let t = ramp();
        assert_eq!(t.bilinear(Vec2::new(0.25, 0.75)).x, 0.0);
        assert_eq!(t.bilinear(Vec2::new(0.75, 0.75)).x, 1.0);
        assert_eq!(t.bilinear(Vec2::new(0.25, 0.25)).x, 2.0);
        assert!((t.bilinear(Vec2::new(0.5, 0.5)).x - 1.5).abs() < 1e-6);
    }

    #[test]
    fn wrap_modes_differ_outside_the_unit_square() {
        let mut t = ramp();
        let outside = Vec2::new(1.25, 0.75);
        assert_eq!(t.bilinear(outside).x, 0.0, "repeat wraps to the left column");
        t.wrap = WrapMode::Clamp;
        assert_eq!(t.bilinear(outside).x, 1.0);
        t.wrap = WrapMode::Black;
        assert_eq!(t.bilinear(Vec2::new(1.75, 0.75)).x, 0.0);
        assert_eq!(t.bilinear(Vec2::new(-0.75, 0.75)).x, 0.0);
    }

    #[test]
    fn checkerboard_scale_and_average() {
        let c = Texture::Checkerboard(Box::new(Checkerboard {
            even: 1.0.into(),
            odd: 0.0.into(),
            mapping: UvMapping { su: 4.0, sv: 4.0, du: 0.0, dv: 0.0 },
        }));
        assert_eq!(c.eval(Vec2::new(0.1, 0.1)).x, 1.0);
        assert_eq!(c.eval(Vec2::new(0.3, 0.1)).x, 0.0);
        assert_eq!(c.eval(Vec2::new(0.3, 0.3)).x, 1.0);
        let s = Texture::Scale(Box::new((c, Rgb::new(2.0, 3.0, 4.0).into())));
        assert_eq!(s.eval(Vec2::new(0.1, 0.1)), Rgb::new(2.0, 3.0, 4.0));
        assert_eq!(s.average(), Rgb::new(1.0, 1.5, 2.0));
        let m = Texture::Mix(Box::new((Rgb::ZERO.into(), Rgb::splat(4.0).into(), 0.25.into())));
        assert_eq!(m.eval(Vec2::ZERO), Rgb::ONE);
    }
}
