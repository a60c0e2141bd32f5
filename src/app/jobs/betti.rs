//! The Betti numbers of every superarc's contours ([`ContourTopology`]),
//! computed once per volume after it is shown, for the tree's tooltips.

use std::sync::Arc;

use super::Job;
use crate::app::dataset::Dataset;
use crate::measure::betti::ContourTopology;

/// The Betti job: its value is the topology of the field it was started
/// for (compared by pointer, so a late answer for another volume is not
/// shown).
pub type BettiJob = Job<(usize, Arc<ContourTopology>)>;

/// A key naming the field of `ds`.
pub fn field_key(ds: &Dataset) -> usize {
    Arc::as_ptr(&ds.field) as usize
}

/// Starts computing the topology of `ds`'s contours.
pub fn start(job: &mut BettiJob, ds: &Dataset) {
    let (tree, field) = (Arc::clone(&ds.tree), Arc::clone(&ds.field));
    let key = field_key(ds);
    job.start("Betti numbers", move |_| {
        Ok((key, Arc::new(ContourTopology::new(&tree, &field))))
    });
}

/// The topology of `ds`'s contours, once computed.
pub fn of(job: &BettiJob, ds: &Dataset) -> Option<Arc<ContourTopology>> {
    job.ready()
        .filter(|(key, _)| *key == field_key(ds))
        .map(|(_, t)| Arc::clone(t))
}
