//! Local geometric measures (in progress).
