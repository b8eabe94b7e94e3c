//! Distributed domain decomposition (work in progress).
