//! The experiment's two families of fields on an n^3 grid, cells of s^3
//! voxels (s = 4): a hill in every cell (heights 970-1100, distinct per
//! cell), separated by walls on the cell faces whose height decides how the
//! hills join.
//!
//! - **Short and fat** ([`short_and_fat`]): a wall at coordinate c = k s
//!   stands at 500 - 10 tz(k) (tz: trailing zero bits), so neighbouring
//!   cells join first in pairs, pairs in pairs, and so on: an octree of
//!   joins, a contour tree of depth O(log t) with t/ (few) maxima.
//! - **Tall and thin** ([`tall_and_thin`]): the walls of cell number k (in
//!   id order) stand at -k, so cell k's hill joins the hills of all earlier
//!   cells at the k-th saddle: a staircase of nested saddles, a contour tree
//!   whose main path holds every join.

use crate::field::{ScalarField, Values};

/// Cell size.
const S: usize = 4;

fn hill(cell: usize, local: [usize; 3]) -> f32 {
    // A deterministic height per cell (an integer hash), distinct per cell
    // up to ties that the vertex order breaks.
    let mut h = (cell as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    h ^= h >> 29;
    let height = 1000.0 + (h % 100_000) as f32 * 0.001;
    let d: usize = local
        .iter()
        .map(|&c| (c as i64 - (S / 2) as i64).pow(2) as usize)
        .sum();
    height - 3.0 * d as f32
}

fn generate(n: usize, wall: impl Fn([usize; 3], usize) -> Option<f32>) -> ScalarField {
    let nc = n.div_ceil(S);
    let mut values = Vec::with_capacity(n * n * n);
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                let p = [x, y, z];
                let cell = x / S + nc * (y / S + nc * (z / S));
                let v = wall(p, cell).unwrap_or_else(|| hill(cell, p.map(|c| c % S)));
                values.push(v);
            }
        }
    }
    ScalarField::new([n, n, n], Values::F32(values)).expect("valid dimensions")
}

/// Hills joined by an octree of walls (see the module doc).
pub fn short_and_fat(n: usize) -> ScalarField {
    let cap = usize::BITS - n.div_ceil(S).leading_zeros() + 1;
    generate(n, |p, _| {
        p.iter()
            .filter(|&&c| c % S == 0)
            .map(|&c| {
                let k = c / S;
                let level = if k == 0 {
                    cap
                } else {
                    k.trailing_zeros().min(cap)
                };
                500.0 - 10.0 * level as f32
            })
            .reduce(f32::min)
    })
}

/// Hills joined one by one down a staircase of saddles (see the module doc).
pub fn tall_and_thin(n: usize) -> ScalarField {
    generate(n, |p, cell| {
        p.iter().any(|&c| c % S == 0).then_some(-(cell as f32))
    })
}
