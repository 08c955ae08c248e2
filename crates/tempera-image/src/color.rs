//! Colour encodings of 8-bit images: the sRGB transfer function (IEC 61966-2-1), linear, and
//! pure gamma, as pbrt-v4's `encoding` parameter names them.

/// How stored values map to linear values.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ColorEncoding {
    Srgb,
    Linear,
    Gamma(f32),
}

impl ColorEncoding {
    /// Decodes a stored value in `[0, 1]` to linear.
    #[inline]
    pub fn decode(self, v: f32) -> f32 {
        match self {
            ColorEncoding::Srgb => srgb_to_linear(v),
            ColorEncoding::Linear => v,
            ColorEncoding::Gamma(g) => v.max(0.0).powf(g),
        }
    }
}

pub fn srgb_to_linear(v: f32) -> f32 {
    if v <= 0.04045 { v / 12.92 } else { ((v + 0.055) / 1.055).powf(2.4) }
}

pub fn linear_to_srgb(v: f32) -> f32 {
    let v = v.clamp(0.0, 1.0);
    if v <= 0.003_130_8 { v * 12.92 } else { 1.055 * v.powf(1.0 / 2.4) - 0.055 }
}
