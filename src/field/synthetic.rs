//! Synthetic fields with known, interesting topology: the program's built-in
//! default dataset and a source of test and benchmark volumes of any size.
//!
//! The default scene has blobs of different sizes and heights (maxima of
//! different persistence and volume), a torus (a contour of genus 1), and a
//! hollow spherical shell around a core blob (a contour that splits into an
//! inside and an outside surface), optionally with deterministic noise.

use super::{ScalarField, Values};
use rayon::prelude::*;

/// What to generate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Synthetic {
    /// Grid size (X, Y, Z).
    pub dims: [usize; 3],
    /// Amplitude of uniform noise added to every value (0 for none).
    pub noise: f32,
    /// Seed of the noise.
    pub seed: u64,
}

impl Default for Synthetic {
    fn default() -> Self {
        Self {
            dims: [128, 128, 128],
            noise: 0.0,
            seed: 1,
        }
    }
}

/// A Gaussian bump: centre and radius in unit-cube coordinates.
struct Blob {
    centre: [f32; 3],
    radius: f32,
    height: f32,
}

const BLOBS: [Blob; 5] = [
    Blob {
        centre: [0.22, 0.25, 0.25],
        radius: 0.09,
        height: 1.0,
    },
    Blob {
        centre: [0.30, 0.70, 0.22],
        radius: 0.06,
        height: 0.8,
    },
    Blob {
        centre: [0.18, 0.45, 0.70],
        radius: 0.04,
        height: 0.65,
    },
    Blob {
        centre: [0.42, 0.30, 0.78],
        radius: 0.025,
        height: 0.55,
    },
    Blob {
        centre: [0.40, 0.82, 0.62],
        radius: 0.05,
        height: 0.9,
    },
];

impl Synthetic {
    /// A scene of the given cubic size, without noise.
    pub fn cube(n: usize) -> Self {
        Self {
            dims: [n, n, n],
            ..Self::default()
        }
    }

    /// The same scene with noise of amplitude `noise`.
    pub fn with_noise(self, noise: f32, seed: u64) -> Self {
        Self {
            noise,
            seed,
            ..self
        }
    }

    /// The value at a point of the unit cube, without noise.
    pub fn value_at(p: [f32; 3]) -> f32 {
        let sq = |a: f32| a * a;
        let mut f = 0.0f32;
        for b in &BLOBS {
            let d2 = sq(p[0] - b.centre[0]) + sq(p[1] - b.centre[1]) + sq(p[2] - b.centre[2]);
            f += b.height * (-d2 / sq(b.radius)).exp();
        }
        // Torus around the z axis through (0.72, 0.28, 0.30).
        let (tx, ty, tz) = (p[0] - 0.72, p[1] - 0.28, p[2] - 0.30);
        let rho = (tx * tx + ty * ty).sqrt();
        let ring = (rho - 0.14).hypot(tz);
        // Height varies around the ring: a ridge of constant height would be
        // a degenerate circle of maxima.
        let around = if rho > 0.0 { tx / rho } else { 0.0 };
        f += 0.85 * (1.0 + 0.4 * around) * (-sq(ring / 0.06)).exp();
        // Hollow shell of radius 0.16 around (0.70, 0.68, 0.66), with a core.
        let (sx, sy, sz) = (p[0] - 0.70, p[1] - 0.68, p[2] - 0.66);
        let r = (sx * sx + sy * sy + sz * sz).sqrt();
        let up = if r > 0.0 { sz / r } else { 0.0 };
        f += 0.7 * (1.0 + 0.5 * up) * (-sq((r - 0.16) / 0.05)).exp();
        f += 0.95 * (-sq(r / 0.05)).exp();
        // A faint tilt: far from every feature the bumps underflow to exactly
        // 0.0, and a plateau would turn into spurious critical points under
        // simulation of simplicity. The tilt adds none of its own.
        f + 0.02 * (p[0] + 0.6 * p[1] + 0.3 * p[2])
    }

    /// Generates the field (float32 values, unit spacing).
    pub fn generate(&self) -> ScalarField {
        let [nx, ny, nz] = self.dims;
        let scale = |i: usize, n: usize| {
            if n > 1 {
                i as f32 / (n - 1) as f32
            } else {
                0.5
            }
        };
        // One z-slice per task, in parallel; the noise depends only on the
        // vertex id, so the field is the same on any number of threads.
        let mut values = vec![0f32; nx * ny * nz];
        values
            .par_chunks_mut((nx * ny).max(1))
            .enumerate()
            .for_each(|(z, slice)| {
                let mut id = (z * nx * ny) as u64;
                for y in 0..ny {
                    for x in 0..nx {
                        let mut f = Self::value_at([scale(x, nx), scale(y, ny), scale(z, nz)]);
                        if self.noise > 0.0 {
                            f += self.noise * unit_noise(self.seed, id);
                        }
                        slice[y * nx + x] = f;
                        id += 1;
                    }
                }
            });
        // Finite by construction, dims nonzero and within the limit for any
        // size a caller can allocate.
        ScalarField::new(self.dims, Values::F32(values))
            .unwrap_or_else(|e| panic!("synthetic field of {:?} is invalid: {e}", self.dims))
    }
}

/// Deterministic noise in [-0.5, 0.5) (splitmix64 of seed and index).
fn unit_noise(seed: u64, i: u64) -> f32 {
    let mut z = seed
        .wrapping_mul(0x9E37_79B9_7F4A_7C15)
        .wrapping_add(i.wrapping_mul(0xBF58_476D_1CE4_E5B9));
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    (z >> 40) as f32 / (1u64 << 24) as f32 - 0.5
}
