//! The scalar field: a regular grid of values, its spacing, where it sits
//! in the world ([`Geometry`]), and the total order on its vertices.
//!
//! Values are kept in the type the file had (a uint8 CT scan stays one byte
//! per voxel). The engine never compares values directly: it works on the
//! *vertex order* ([`ScalarField::vertex_order`]), the vertices sorted by
//! value with ties broken by vertex id (simulation of simplicity), so every
//! vertex has a distinct place and the contour tree is well defined.
//!
//! Vertex ids are `u32`: `id = x + X * (y + Y * z)`. The engine reserves the
//! top bit of some per-vertex words, so a field holds at most
//! [`MAX_VERTICES`] vertices (about 1290^3).

mod geometry;
pub mod io;
mod order;
pub mod slice;
pub mod source;
pub mod synthetic;

pub use geometry::{Geometry, GeometryError, Space};
pub use order::{
    NARROW_VERTICES, Order, OrderView, PackedOrder, compact_vertex_order, ids_bytes, narrow_id,
    order_bytes, sorts_by_counting, vertex_order, wide_id,
};

use rayon::prelude::*;
use thiserror::Error;

/// Values per task of a scan over a field's values.
const SCAN_CHUNK: usize = 1 << 20;

/// The largest number of vertices the engine accepts (ids are `u32` and the
/// top bit is reserved).
pub const MAX_VERTICES: usize = (1 << 31) - 1;

/// The values of a field, in the compact type they were stored in.
#[derive(Clone, Debug, PartialEq)]
pub enum Values {
    /// Unsigned 8-bit.
    U8(Vec<u8>),
    /// Signed 8-bit.
    I8(Vec<i8>),
    /// Unsigned 16-bit.
    U16(Vec<u16>),
    /// Signed 16-bit.
    I16(Vec<i16>),
    /// Unsigned 32-bit.
    U32(Vec<u32>),
    /// Signed 32-bit.
    I32(Vec<i32>),
    /// 32-bit float (never NaN or infinite once in a [`ScalarField`]).
    F32(Vec<f32>),
    /// 64-bit float (never NaN or infinite once in a [`ScalarField`]).
    F64(Vec<f64>),
}

/// Runs `$body` with `$v` bound to the typed slice inside a [`Values`].
#[macro_export]
macro_rules! with_values {
    ($values:expr, $v:ident => $body:expr) => {
        match $values {
            $crate::field::Values::U8($v) => $body,
            $crate::field::Values::I8($v) => $body,
            $crate::field::Values::U16($v) => $body,
            $crate::field::Values::I16($v) => $body,
            $crate::field::Values::U32($v) => $body,
            $crate::field::Values::I32($v) => $body,
            $crate::field::Values::F32($v) => $body,
            $crate::field::Values::F64($v) => $body,
        }
    };
}

/// A scalar type the field can hold.
pub trait Scalar: Copy + PartialOrd + Send + Sync + 'static {
    /// The value as f64 (exact for every type but u64-range integers).
    fn to_f64(self) -> f64;
}

/// The total order on vertices the engine sweeps in: by value, ties by id
/// (simulation of simplicity).
pub trait VertexOrder: Sync {
    /// True when vertex `a` comes after vertex `b`.
    fn above(&self, a: u32, b: u32) -> bool;

    /// The order of `a` and `b` as an [`std::cmp::Ordering`], for sorts:
    /// one comparison, equal only for the same vertex.
    #[inline(always)]
    fn ordering(&self, a: u32, b: u32) -> std::cmp::Ordering {
        if a == b {
            std::cmp::Ordering::Equal
        } else if self.above(a, b) {
            std::cmp::Ordering::Greater
        } else {
            std::cmp::Ordering::Less
        }
    }

    /// For the consecutive vertices `v = first + i` (one per entry of
    /// `out`), the bit mask of the `offsets` whose vertex comes after `v`:
    /// bit `j` of `out[i]` is [`Self::above`]`(v + offsets[j], v)`. Every
    /// `v + offsets[j]` must be a vertex. What the link classification of a
    /// grid's interior rows asks, a row at a time.
    fn above_masks(&self, first: u32, offsets: &[i64], out: &mut [u16]) {
        for (i, m) in out.iter_mut().enumerate() {
            let v = first + i as u32;
            *m = offsets.iter().enumerate().fold(0, |m, (j, &o)| {
                m | (self.above((v as i64 + o) as u32, v) as u16) << j
            });
        }
    }
}

impl<T: Scalar> VertexOrder for [T] {
    #[inline(always)]
    fn above(&self, a: u32, b: u32) -> bool {
        let (fa, fb) = (self[a as usize], self[b as usize]);
        fa > fb || (fa == fb && a > b)
    }

    /// One offset at a time over the whole run, comparing values alone: a
    /// vertex at a positive offset has the larger id, so it is above iff
    /// its value is `>=`, and at a negative offset iff `>` (the same answer
    /// as [`Self::above`] for every value, NaN and -0.0 included). Plain
    /// loops over slices, which the compiler turns into vector compares.
    fn above_masks(&self, first: u32, offsets: &[i64], out: &mut [u16]) {
        let (first, len) = (first as usize, out.len());
        let centre = &self[first..first + len];
        out.fill(0);
        for (j, &o) in offsets.iter().enumerate() {
            let start = (first as i64 + o) as usize;
            let other = &self[start..start + len];
            if o > 0 {
                for ((m, &a), &b) in out.iter_mut().zip(other).zip(centre) {
                    *m |= ((a >= b) as u16) << j;
                }
            } else {
                for ((m, &a), &b) in out.iter_mut().zip(other).zip(centre) {
                    *m |= ((a > b) as u16) << j;
                }
            }
        }
    }
}

/// An isovalue as a cut in the vertex order: vertex `v` is *above* it iff
/// `(f(v), v) > (value, tie)` lexicographically, the same simulation of
/// simplicity the vertex order breaks ties by. A level set is then never
/// *on* a vertex: every edge it crosses has one end strictly on each side.
///
/// [`Isovalue::new`] puts the cut just above every vertex of value `h`
/// (`tie = u32::MAX`): the level set at `h + ε`.
/// [`Isovalue::just_above`] cuts between one vertex and the next.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Isovalue {
    /// The value, in the field's units.
    pub value: f64,
    /// Vertices of exactly `value` are above iff their id exceeds `tie`.
    pub tie: u32,
}

impl Isovalue {
    /// The level set at `h + ε`: every vertex of value `h` lies below.
    pub fn new(h: f64) -> Self {
        Self {
            value: h,
            tie: u32::MAX,
        }
    }

    /// The cut just above vertex `v` in the vertex order: `v` and every
    /// vertex before it lie below, every later vertex above.
    pub fn just_above(field: &ScalarField, v: u32) -> Self {
        Self {
            value: field.value(v),
            tie: v,
        }
    }

    /// True when vertex `v` of value `f` lies above the cut.
    #[inline(always)]
    pub fn above_value(&self, f: f64, v: u32) -> bool {
        f > self.value || (f == self.value && v > self.tie)
    }

    /// True when vertex `v` of `field` lies above the cut.
    #[inline]
    pub fn is_above(&self, field: &ScalarField, v: u32) -> bool {
        self.above_value(field.value(v), v)
    }
}

macro_rules! impl_scalar {
    ($($t:ty),*) => {$(
        impl Scalar for $t {
            #[inline]
            fn to_f64(self) -> f64 {
                self as f64
            }
        }
    )*};
}
impl_scalar!(u8, i8, u16, i16, u32, i32, f32, f64);

impl Values {
    /// Number of values.
    pub fn len(&self) -> usize {
        with_values!(self, v => v.len())
    }

    /// True when there are no values.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The value at `i` as f64.
    #[inline]
    pub fn get(&self, i: usize) -> f64 {
        with_values!(self, v => v[i].to_f64())
    }

    /// The name of the stored type, as NRRD spells it.
    pub fn type_name(&self) -> &'static str {
        match self {
            Values::U8(_) => "uint8",
            Values::I8(_) => "int8",
            Values::U16(_) => "uint16",
            Values::I16(_) => "int16",
            Values::U32(_) => "uint32",
            Values::I32(_) => "int32",
            Values::F32(_) => "float32",
            Values::F64(_) => "float64",
        }
    }

    /// Bytes per stored value.
    pub fn bytes_per_value(&self) -> usize {
        match self {
            Values::U8(_) | Values::I8(_) => 1,
            Values::U16(_) | Values::I16(_) => 2,
            Values::U32(_) | Values::I32(_) | Values::F32(_) => 4,
            Values::F64(_) => 8,
        }
    }

    /// Count of NaN or infinite values and the index of the first one.
    /// Parts of the values on every core: a volume of a GiB is read in a
    /// fraction of a second, not one core's second.
    pub fn non_finite(&self) -> Option<(usize, usize)> {
        fn scan<T: Scalar>(v: &[T]) -> Option<(usize, usize)> {
            let (count, first) = v
                .par_chunks(SCAN_CHUNK)
                .enumerate()
                .map(|(c, part)| {
                    let bad = |x: &T| !x.to_f64().is_finite();
                    let count = part.iter().filter(|x| bad(x)).count();
                    let first = part.iter().position(bad).map(|i| c * SCAN_CHUNK + i);
                    (count, first)
                })
                .reduce(|| (0, None), |(c1, f1), (c2, f2)| (c1 + c2, f1.or(f2)));
            first.map(|f| (count, f))
        }
        match self {
            Values::F32(v) => scan(v),
            Values::F64(v) => scan(v),
            _ => None,
        }
    }

    /// Smallest and largest value (0, 0 when empty), parts of the values on
    /// every core.
    pub fn range(&self) -> (f64, f64) {
        fn mm<T: Scalar>(v: &[T]) -> (f64, f64) {
            let extremes = |part: &[T]| {
                let mut it = part.iter();
                let &first = it.next()?;
                let (mut lo, mut hi) = (first, first);
                for &x in it {
                    if x < lo {
                        lo = x;
                    }
                    if x > hi {
                        hi = x;
                    }
                }
                Some((lo.to_f64(), hi.to_f64()))
            };
            v.par_chunks(SCAN_CHUNK)
                .filter_map(extremes)
                .reduce_with(|(l1, h1), (l2, h2)| (l1.min(l2), h1.max(h2)))
                .unwrap_or((0.0, 0.0))
        }
        with_values!(self, v => mm(v))
    }
}

/// Why a field could not be made from the values given.
#[derive(Debug, Error, PartialEq)]
pub enum FieldError {
    /// A dimension is zero.
    #[error("dimensions {0:?} contain a zero")]
    ZeroDimension([usize; 3]),
    /// The product of the dimensions overflows or exceeds the engine's limit.
    #[error("dimensions {0:?} give more than {MAX_VERTICES} vertices, the engine's limit")]
    TooLarge([usize; 3]),
    /// The number of values does not match the dimensions.
    #[error("dimensions {dims:?} need {expected} values but {found} were given")]
    CountMismatch {
        /// Dimensions given.
        dims: [usize; 3],
        /// Their product.
        expected: usize,
        /// Values found.
        found: usize,
    },
    /// Some values are NaN or infinite.
    #[error("{count} values are NaN or infinite (first at vertex {first}, x={x} y={y} z={z})")]
    NonFinite {
        /// How many.
        count: usize,
        /// Linear index of the first.
        first: usize,
        /// Its x.
        x: usize,
        /// Its y.
        y: usize,
        /// Its z.
        z: usize,
    },
    /// A spacing is not a positive finite number.
    #[error("spacing {0:?} must be positive and finite")]
    BadSpacing([f64; 3]),
}

/// The number of vertices of a grid of `dims`, checked against overflow and
/// the engine's limit.
pub fn checked_vertex_count(dims: [usize; 3]) -> Result<usize, FieldError> {
    if dims.contains(&0) {
        return Err(FieldError::ZeroDimension(dims));
    }
    dims[0]
        .checked_mul(dims[1])
        .and_then(|n| n.checked_mul(dims[2]))
        .filter(|&n| n <= MAX_VERTICES)
        .ok_or(FieldError::TooLarge(dims))
}

/// A scalar field sampled on a regular grid (Z = 1 for a 2D image).
#[derive(Clone, Debug, PartialEq)]
pub struct ScalarField {
    dims: [usize; 3],
    spacing: [f64; 3],
    geometry: Geometry,
    values: Values,
}

impl ScalarField {
    /// A field with unit spacing. Fails on zero or too large dimensions, a
    /// count that does not match, and NaN or infinite values.
    pub fn new(dims: [usize; 3], values: Values) -> Result<Self, FieldError> {
        Self::with_spacing(dims, [1.0; 3], values)
    }

    /// A field with the given voxel spacing.
    pub fn with_spacing(
        dims: [usize; 3],
        spacing: [f64; 3],
        values: Values,
    ) -> Result<Self, FieldError> {
        let expected = checked_vertex_count(dims)?;
        if values.len() != expected {
            return Err(FieldError::CountMismatch {
                dims,
                expected,
                found: values.len(),
            });
        }
        if spacing.iter().any(|s| !(s.is_finite() && *s > 0.0)) {
            return Err(FieldError::BadSpacing(spacing));
        }
        if let Some((count, first)) = values.non_finite() {
            return Err(FieldError::NonFinite {
                count,
                first,
                x: first % dims[0],
                y: first / dims[0] % dims[1],
                z: first / (dims[0] * dims[1]),
            });
        }
        Ok(Self {
            dims,
            spacing,
            geometry: Geometry::IDENTITY,
            values,
        })
    }

    /// The same field placed in the world by `geometry`.
    pub fn with_geometry(mut self, geometry: Geometry) -> Self {
        self.geometry = geometry;
        self
    }

    /// Where the grid sits in the world.
    pub fn geometry(&self) -> &Geometry {
        &self.geometry
    }

    /// The world position of vertex `v`: origin + direction · (index ×
    /// spacing).
    pub fn world_position(&self, v: u32) -> [f64; 3] {
        let c = self.coords(v);
        self.geometry
            .to_world(std::array::from_fn(|a| c[a] as f64 * self.spacing[a]))
    }

    /// Grid dimensions (X, Y, Z).
    pub fn dims(&self) -> [usize; 3] {
        self.dims
    }

    /// Voxel spacing along X, Y, Z.
    pub fn spacing(&self) -> [f64; 3] {
        self.spacing
    }

    /// The stored values.
    pub fn values(&self) -> &Values {
        &self.values
    }

    /// Number of vertices.
    pub fn len(&self) -> usize {
        self.values.len()
    }

    /// Never true for a valid field; here for clippy's sake.
    pub fn is_empty(&self) -> bool {
        self.values.is_empty()
    }

    /// The value of vertex `v` as f64, in the file's units.
    #[inline]
    pub fn value(&self, v: u32) -> f64 {
        self.values.get(v as usize)
    }

    /// True when `a` comes after `b` in the vertex order: higher value, or
    /// equal value and higher id (simulation of simplicity).
    #[inline]
    pub fn is_above(&self, a: u32, b: u32) -> bool {
        with_values!(&self.values, v => v.above(a, b))
    }

    /// The vertices sorted ascending by (value, id).
    pub fn vertex_order(&self) -> Vec<u32> {
        vertex_order(&self.values)
    }

    /// The same order in the form that takes least memory
    /// ([`compact_vertex_order`]).
    pub fn compact_vertex_order(&self) -> Order {
        compact_vertex_order(&self.values)
    }

    /// (x, y, z) of vertex `v`.
    #[inline]
    pub fn coords(&self, v: u32) -> [usize; 3] {
        let v = v as usize;
        let [x, y, _] = self.dims;
        [v % x, v / x % y, v / (x * y)]
    }

    /// Smallest and largest value.
    pub fn range(&self) -> (f64, f64) {
        self.values.range()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(12))]
        /// The scans over parts of the values on every core find what one
        /// scan from the start finds: the count and first position of the
        /// values that are not finite, and the extremes, whichever part of
        /// the values (past the first) they lie in.
        #[test]
        fn scans_in_parts_are_the_scan_from_the_start(
            len in 0usize..(2 * SCAN_CHUNK + SCAN_CHUNK / 2),
            bad in proptest::collection::vec((any::<prop::sample::Index>(), 0usize..3), 0..4),
            seed in any::<u32>(),
        ) {
            let mut v: Vec<f32> = (0..len as u32)
                .map(|i| ((i ^ seed).wrapping_mul(2_654_435_761) >> 8) as f32 - 1e6)
                .collect();
            let finite = v.clone();
            for (at, kind) in &bad {
                if len > 0 {
                    v[at.index(len)] = [f32::NAN, f32::INFINITY, f32::NEG_INFINITY][*kind];
                }
            }
            let expect = {
                let is_bad: Vec<usize> = (0..len).filter(|&i| !v[i].is_finite()).collect();
                is_bad.first().map(|&f| (is_bad.len(), f))
            };
            prop_assert_eq!(Values::F32(v).non_finite(), expect);
            let lo = finite.iter().copied().fold(f32::INFINITY, f32::min);
            let hi = finite.iter().copied().fold(f32::NEG_INFINITY, f32::max);
            let expect = if len == 0 { (0.0, 0.0) } else { (lo as f64, hi as f64) };
            prop_assert_eq!(Values::F32(finite).range(), expect);
        }
    }
}
