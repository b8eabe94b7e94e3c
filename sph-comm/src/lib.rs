//! Communicator abstraction (work in progress).
