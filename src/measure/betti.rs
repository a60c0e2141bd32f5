//! Betti numbers of contours per superarc (in progress).
