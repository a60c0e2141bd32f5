//! The regular vertices of every superarc, one list of all of them grouped
//! by superarc (`ContourTree::arc_vertices`), held in 3 bytes per vertex
//! id where the mesh has at most [`NARROW_VERTICES`] vertices (a 256³
//! volume, every shared scan) and in 4 otherwise: the form of
//! [`crate::field::Order::Narrow`], whose ids these are, regrouped.
//!
//! In the finished tree the lists are the largest thing but for the
//! places (3 bytes per vertex): 4 bytes per regular vertex made tooth's
//! tree 11.15 bytes per vertex and its build's peak (12.0-12.4); in 3 the
//! tree is a byte per regular vertex smaller, and so is the grouping that
//! writes them (beside the order and the places). The grouping writes the
//! entries in place ([`Entry`]), on every core; readers get an
//! [`ArcVertices`], a slice of either form that reads as ids.

use crate::field::{NARROW_VERTICES, narrow_id, wide_id};
use std::ops::Range;

/// A vertex id as the lists store it: a whole word, or 3 bytes.
pub(crate) trait Entry: Copy + Send + Sync + 'static {
    /// The entry of id `v`.
    fn entry(v: u32) -> Self;
}

impl Entry for u32 {
    #[inline(always)]
    fn entry(v: u32) -> Self {
        v
    }
}

impl Entry for [u8; 3] {
    #[inline(always)]
    fn entry(v: u32) -> Self {
        debug_assert!((v as usize) < NARROW_VERTICES);
        narrow_id(v)
    }
}

/// The lists of a mesh's regular vertices, in one of the two forms.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) enum VertexLists {
    /// Ids in 4 bytes.
    Wide(Vec<u32>),
    /// Ids in 3 bytes.
    Narrow(Vec<[u8; 3]>),
}

impl VertexLists {
    /// True when a mesh of `n` vertices keeps its lists narrow.
    pub(crate) fn narrows(n: usize) -> bool {
        n <= NARROW_VERTICES
    }

    /// Bytes per regular vertex for a mesh of `n` vertices.
    pub(crate) fn bytes_per_vertex(n: usize) -> u64 {
        if Self::narrows(n) { 3 } else { 4 }
    }

    /// `ids` in the form a mesh of `n` vertices keeps.
    pub(crate) fn of_ids(ids: Vec<u32>, n: usize) -> Self {
        if Self::narrows(n) {
            VertexLists::Narrow(ids.into_iter().map(narrow_id).collect())
        } else {
            VertexLists::Wide(ids)
        }
    }

    /// The entries at `range`.
    #[inline]
    pub(crate) fn slice(&self, range: Range<usize>) -> ArcVertices<'_> {
        match self {
            VertexLists::Wide(ids) => ArcVertices::Wide(&ids[range]),
            VertexLists::Narrow(ids) => ArcVertices::Narrow(&ids[range]),
        }
    }

    /// Heap bytes.
    pub(crate) fn heap_bytes(&self) -> usize {
        match self {
            VertexLists::Wide(ids) => ids.capacity() * 4,
            VertexLists::Narrow(ids) => ids.capacity() * 3,
        }
    }
}

/// Vertex ids in a row of the lists (one superarc's, or part of one): a
/// slice of 4-byte or 3-byte ids, read as ids.
#[derive(Clone, Copy)]
pub enum ArcVertices<'a> {
    /// Ids in 4 bytes.
    Wide(&'a [u32]),
    /// Ids in 3 bytes, little end first.
    Narrow(&'a [[u8; 3]]),
}

impl<'a> ArcVertices<'a> {
    /// Number of vertices.
    #[inline]
    pub fn len(self) -> usize {
        match self {
            ArcVertices::Wide(ids) => ids.len(),
            ArcVertices::Narrow(ids) => ids.len(),
        }
    }

    /// True if there are none.
    #[inline]
    pub fn is_empty(self) -> bool {
        self.len() == 0
    }

    /// The `i`-th id, if there is one.
    #[inline]
    pub fn get(self, i: usize) -> Option<u32> {
        match self {
            ArcVertices::Wide(ids) => ids.get(i).copied(),
            ArcVertices::Narrow(ids) => ids.get(i).map(|&b| wide_id(b)),
        }
    }

    /// The first id.
    #[inline]
    pub fn first(self) -> Option<u32> {
        self.get(0)
    }

    /// The last id.
    #[inline]
    pub fn last(self) -> Option<u32> {
        self.len().checked_sub(1).and_then(|i| self.get(i))
    }

    /// The ids at positions `range` (panics out of bounds, as a slice).
    #[inline]
    pub fn slice(self, range: Range<usize>) -> Self {
        match self {
            ArcVertices::Wide(ids) => ArcVertices::Wide(&ids[range]),
            ArcVertices::Narrow(ids) => ArcVertices::Narrow(&ids[range]),
        }
    }

    /// The ids in turn.
    #[inline]
    pub fn iter(self) -> Iter<'a> {
        Iter(match self {
            ArcVertices::Wide(ids) => Ids::Wide(ids.iter()),
            ArcVertices::Narrow(ids) => Ids::Narrow(ids.iter()),
        })
    }

    /// The first position whose id fails `pred`, where every id that
    /// passes comes before every id that fails (as
    /// [`slice::partition_point`]).
    pub fn partition_point(self, mut pred: impl FnMut(u32) -> bool) -> usize {
        match self {
            ArcVertices::Wide(ids) => ids.partition_point(|&v| pred(v)),
            ArcVertices::Narrow(ids) => ids.partition_point(|&b| pred(wide_id(b))),
        }
    }

    /// The ids as a vector.
    pub fn to_vec(self) -> Vec<u32> {
        self.iter().collect()
    }
}

impl PartialEq for ArcVertices<'_> {
    fn eq(&self, other: &Self) -> bool {
        self.len() == other.len() && self.iter().eq(other.iter())
    }
}

impl Eq for ArcVertices<'_> {}

impl std::fmt::Debug for ArcVertices<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_list().entries(self.iter()).finish()
    }
}

impl<'a> IntoIterator for ArcVertices<'a> {
    type Item = u32;
    type IntoIter = Iter<'a>;

    fn into_iter(self) -> Iter<'a> {
        self.iter()
    }
}

/// The ids of an [`ArcVertices`] in turn.
#[derive(Clone, Debug)]
pub struct Iter<'a>(Ids<'a>);

#[derive(Clone, Debug)]
enum Ids<'a> {
    Wide(std::slice::Iter<'a, u32>),
    Narrow(std::slice::Iter<'a, [u8; 3]>),
}

impl Iterator for Iter<'_> {
    type Item = u32;

    #[inline]
    fn next(&mut self) -> Option<u32> {
        match &mut self.0 {
            Ids::Wide(ids) => ids.next().copied(),
            Ids::Narrow(ids) => ids.next().map(|&b| wide_id(b)),
        }
    }

    #[inline]
    fn size_hint(&self) -> (usize, Option<usize>) {
        let n = match &self.0 {
            Ids::Wide(ids) => ids.len(),
            Ids::Narrow(ids) => ids.len(),
        };
        (n, Some(n))
    }

    /// One match for the whole run (sums and `for_each` go through it).
    #[inline]
    fn fold<B, F: FnMut(B, u32) -> B>(self, init: B, mut f: F) -> B {
        match self.0 {
            Ids::Wide(ids) => ids.fold(init, |acc, &v| f(acc, v)),
            Ids::Narrow(ids) => ids.fold(init, |acc, &b| f(acc, wide_id(b))),
        }
    }
}

impl DoubleEndedIterator for Iter<'_> {
    #[inline]
    fn next_back(&mut self) -> Option<u32> {
        match &mut self.0 {
            Ids::Wide(ids) => ids.next_back().copied(),
            Ids::Narrow(ids) => ids.next_back().map(|&b| wide_id(b)),
        }
    }
}

impl ExactSizeIterator for Iter<'_> {}

impl std::iter::FusedIterator for Iter<'_> {}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn both_forms_read_the_same_ids() {
        let ids: Vec<u32> = vec![0, 1, 255, 256, 65_535, 65_536, (1 << 24) - 1, 7];
        let wide = VertexLists::Wide(ids.clone());
        let narrow = VertexLists::of_ids(ids.clone(), NARROW_VERTICES);
        assert!(matches!(narrow, VertexLists::Narrow(_)));
        assert!(matches!(
            VertexLists::of_ids(ids.clone(), NARROW_VERTICES + 1),
            VertexLists::Wide(_)
        ));
        for lists in [&wide, &narrow] {
            let all = lists.slice(0..ids.len());
            assert_eq!(all.to_vec(), ids);
            assert_eq!(
                all.iter().rev().collect::<Vec<_>>(),
                ids.iter().rev().copied().collect::<Vec<_>>()
            );
            assert_eq!(
                all.iter().fold(0u64, |s, v| s + u64::from(v)),
                ids.iter().map(|&v| u64::from(v)).sum::<u64>()
            );
            assert_eq!(all.slice(2..5).to_vec(), ids[2..5]);
            assert_eq!(all.first(), Some(0));
            assert_eq!(all.last(), Some(7));
            assert_eq!(all.get(6), Some((1 << 24) - 1));
            assert_eq!(all.get(8), None);
            assert_eq!(all.slice(0..7).partition_point(|v| v < 300), 4);
            assert_eq!(all.iter().len(), 8);
        }
        assert_eq!(wide.slice(1..4), narrow.slice(1..4));
        assert_ne!(wide.slice(1..4), narrow.slice(1..5));
        assert_eq!(narrow.heap_bytes(), 3 * ids.len());
        assert_eq!(format!("{:?}", narrow.slice(0..3)), "[0, 1, 255]");
    }
}
