//! Self-gravity on the octree (work in progress).
