//! Counting value comparisons: a [`VertexOrder`] wrapper that counts every
//! call of [`VertexOrder::above`], and the trait the engines read the count
//! through. Without the wrapper nothing is counted and nothing is paid: the
//! engines are generic over the order, so the plain value slice compiles to
//! the same code as before.

use crate::field::{Scalar, VertexOrder};
use std::sync::atomic::{AtomicU64, Ordering};

/// A vertex order that may know how many comparisons were made on it, and
/// whose vertices may be compared by keys kept elsewhere.
pub trait CountingOrder: VertexOrder {
    /// What a vertex is compared by besides its id (its value): a search
    /// or a heap that compares against the same vertices again and again
    /// keeps their keys beside its own records instead of reading the
    /// field at random.
    type Key: Copy + Send + Sync;

    /// The key of `v` (a read, not a comparison).
    fn key(&self, v: u32) -> Self::Key;

    /// `above(a, b)` given the keys of `a` and `b`: the same answer, and
    /// one comparison like it. `a` and `b` only break ties, so any ids in
    /// the same order as the vertex ids do.
    fn above_keys(&self, ka: Self::Key, a: u32, kb: Self::Key, b: u32) -> bool;

    /// Comparisons made so far (0 for an order that does not count).
    fn comparisons(&self) -> u64 {
        0
    }
}

impl<T: Scalar> CountingOrder for [T] {
    type Key = T;

    #[inline(always)]
    fn key(&self, v: u32) -> T {
        self[v as usize]
    }

    #[inline(always)]
    fn above_keys(&self, fa: T, a: u32, fb: T, b: u32) -> bool {
        // The same test as `VertexOrder for [T]`.
        fa > fb || (fa == fb && a > b)
    }
}

/// Counts the comparisons made on an inner order (one relaxed atomic add
/// each, so the engines' parallel stages may share it).
pub struct Counted<'a, O: ?Sized> {
    inner: &'a O,
    count: AtomicU64,
}

impl<'a, O: VertexOrder + ?Sized> Counted<'a, O> {
    /// Wraps `inner`, the count at zero.
    pub fn new(inner: &'a O) -> Self {
        Self {
            inner,
            count: AtomicU64::new(0),
        }
    }
}

impl<O: VertexOrder + ?Sized> VertexOrder for Counted<'_, O> {
    #[inline]
    fn above(&self, a: u32, b: u32) -> bool {
        self.count.fetch_add(1, Ordering::Relaxed);
        self.inner.above(a, b)
    }
}

impl<O: CountingOrder + ?Sized> CountingOrder for Counted<'_, O> {
    type Key = O::Key;

    #[inline]
    fn key(&self, v: u32) -> O::Key {
        self.inner.key(v)
    }

    #[inline]
    fn above_keys(&self, ka: O::Key, a: u32, kb: O::Key, b: u32) -> bool {
        self.count.fetch_add(1, Ordering::Relaxed);
        self.inner.above_keys(ka, a, kb, b)
    }

    fn comparisons(&self) -> u64 {
        self.count.load(Ordering::Relaxed)
    }
}

/// The inverted order (the field negated, ties by id reversed), under which
/// the split tree is the join tree: `above(a, b)` is `inner.above(b, a)`.
pub struct Inverted<'a, O: ?Sized>(pub &'a O);

impl<O: VertexOrder + ?Sized> VertexOrder for Inverted<'_, O> {
    #[inline(always)]
    fn above(&self, a: u32, b: u32) -> bool {
        self.0.above(b, a)
    }
}

impl<O: CountingOrder + ?Sized> CountingOrder for Inverted<'_, O> {
    type Key = O::Key;

    #[inline(always)]
    fn key(&self, v: u32) -> O::Key {
        self.0.key(v)
    }

    #[inline(always)]
    fn above_keys(&self, ka: O::Key, a: u32, kb: O::Key, b: u32) -> bool {
        self.0.above_keys(kb, b, ka, a)
    }

    fn comparisons(&self) -> u64 {
        self.0.comparisons()
    }
}

/// The comparisons the current engine ([`crate::tree::ContourTree::build`])
/// makes on a field.
#[derive(Clone, Copy, Debug)]
pub struct EngineComparisons {
    /// How the vertex order is sorted for this value type.
    pub sort_kind: &'static str,
    /// Comparisons of that sort (0 for counting and radix sorts, which
    /// compare no two values).
    pub sort: u64,
    /// Comparisons of the link classification and both sweeps (the merge
    /// and augmentation compare none: they read the sorted order).
    pub sweeps: u64,
    /// n log2 n: what a comparison sort of all vertices needs, the
    /// reference the paper measures against.
    pub n_log2_n: f64,
}

impl EngineComparisons {
    /// Sort and sweeps.
    pub fn total(&self) -> u64 {
        self.sort + self.sweeps
    }
}

/// Runs the current engine on `field` with every comparison counted.
pub fn engine_comparisons(
    field: &crate::field::ScalarField,
    progress: &crate::progress::Progress,
) -> Result<(crate::tree::ContourTree, EngineComparisons), crate::tree::BuildError> {
    use crate::field::Values;
    let n = field.len();
    let (sort_kind, sort) = match field.values() {
        Values::U8(_) | Values::I8(_) | Values::U16(_) | Values::I16(_) => ("counting sort", 0),
        Values::U32(_) | Values::I32(_) | Values::F32(_) => ("radix sort", 0),
        Values::F64(v) => {
            // The same comparison sort as the engine's, counted.
            let count = AtomicU64::new(0);
            let mut ids: Vec<u32> = (0..v.len() as u32).collect();
            use rayon::prelude::*;
            ids.par_sort_unstable_by(|&a, &b| {
                count.fetch_add(1, Ordering::Relaxed);
                v[a as usize].total_cmp(&v[b as usize]).then(a.cmp(&b))
            });
            ("comparison sort", count.load(Ordering::Relaxed))
        }
    };
    let order = field.vertex_order();
    let mesh = field.mesh();
    let (tree, sweeps) = crate::with_values!(field.values(), v => {
        let counted = Counted::new(v.as_slice());
        let (tree, _) = crate::tree::ContourTree::build(&mesh, &counted, &order, progress)?;
        (tree, counted.comparisons())
    });
    Ok((
        tree,
        EngineComparisons {
            sort_kind,
            sort,
            sweeps,
            n_log2_n: n as f64 * (n.max(1) as f64).log2(),
        },
    ))
}
