//! What collapsing, measuring and simplifying a contour tree take beyond
//! the tree, checked before each starts. On a tree of tens of millions of
//! superarcs (a noisy 1024³ scan has 87 M) they need more memory than the
//! tree itself, and a process that runs out is killed by the kernel
//! without a word: a clear refusal is better.
//!
//! Peaks measured by sampling the resident size (tooth, engine,
//! colin27_ch2): collapsing and measuring ([`super::CollapsedTree::new`])
//! 150-180 bytes per superarc beyond the tree (the region summaries of
//! both sides of every superarc and the collapse's own tables, side by
//! side); the pruning sequence ([`super::Simplification::from_collapsed`])
//! 115-155 bytes per collapsed arc beyond the collapsed tree. The
//! estimates below are a little above both.

use thiserror::Error;

/// Bytes per superarc that collapsing and measuring a tree take at their
/// peak, beyond the tree.
pub const COLLAPSE_BYTES_PER_SUPERARC: u64 = 190;

/// Bytes per collapsed arc that building the pruning sequence takes at
/// its peak, beyond the collapsed tree.
pub const SIMPLIFICATION_BYTES_PER_ARC: u64 = 160;

/// A stage refused because it would not fit in the memory left.
#[derive(Debug, Error, PartialEq, Eq)]
#[error(
    "{stage} the contour tree's {arcs} arcs needs about {} MiB more, but only {} MiB are available",
    needed >> 20,
    available >> 20
)]
pub struct OutOfMemory {
    /// What was refused.
    pub stage: &'static str,
    /// The arcs it would work on.
    pub arcs: usize,
    /// Bytes it would need at its peak.
    pub needed: u64,
    /// Bytes available.
    pub available: u64,
}

/// Whether collapsing and measuring a tree of `superarcs` superarcs fits
/// in the memory available now.
pub fn check_collapse(superarcs: usize) -> Result<(), OutOfMemory> {
    check(
        "collapsing and measuring",
        superarcs,
        COLLAPSE_BYTES_PER_SUPERARC,
        crate::field::io::available_memory(),
    )
}

/// Whether the pruning sequence of a collapsed tree of `arcs` arcs fits in
/// the memory available now.
pub fn check_simplification(arcs: usize) -> Result<(), OutOfMemory> {
    check(
        "simplifying",
        arcs,
        SIMPLIFICATION_BYTES_PER_ARC,
        crate::field::io::available_memory(),
    )
}

/// `arcs` at `per_arc` bytes against `available` (unknown: allowed).
fn check(
    stage: &'static str,
    arcs: usize,
    per_arc: u64,
    available: Option<u64>,
) -> Result<(), OutOfMemory> {
    let needed = (arcs as u64).saturating_mul(per_arc);
    match available {
        Some(available) if needed > available => Err(OutOfMemory {
            stage,
            arcs,
            needed,
            available,
        }),
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_stage_is_refused_only_when_it_does_not_fit() {
        let arcs = 87_483_003; // the noisy 1024³ scan's superarcs
        let needed = arcs as u64 * COLLAPSE_BYTES_PER_SUPERARC;
        assert!(
            check(
                "collapsing",
                arcs,
                COLLAPSE_BYTES_PER_SUPERARC,
                Some(needed)
            )
            .is_ok()
        );
        assert!(check("collapsing", arcs, COLLAPSE_BYTES_PER_SUPERARC, None).is_ok());
        let e = check(
            "collapsing and measuring",
            arcs,
            COLLAPSE_BYTES_PER_SUPERARC,
            Some(needed - 1),
        )
        .expect_err("refused");
        assert_eq!(e.needed, needed);
        let message = e.to_string();
        assert!(
            message.starts_with("collapsing and measuring the contour tree's 87483003 arcs"),
            "{message}"
        );
        assert!(message.contains("15851 MiB more"), "{message}");
        // A small tree always fits on any machine that built it.
        assert!(check_collapse(1000).is_ok());
        assert!(check_simplification(1000).is_ok());
    }
}
