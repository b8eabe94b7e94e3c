//! Element types that can be communicated.

use std::fmt::Debug;

mod sealed {
    /// Seals [`super::Plain`]; with MPI it also brings the MPI datatype.
    #[cfg(feature = "mpi")]
    pub trait Sealed: mpi::traits::Equivalence {}
    /// Seals [`super::Plain`].
    #[cfg(not(feature = "mpi"))]
    pub trait Sealed {}

    /// Seals [`super::Reducible`]; brings the element-wise reduction used by
    /// the in-process communicator.
    pub trait SealedReduce: Sized {
        /// `a op b`. Integer sums wrap (like MPI's); `Min`/`Max` keep `a`
        /// unless `b` compares strictly smaller/larger.
        fn combine(a: Self, b: Self, op: super::ReduceOp) -> Self;
    }
}

/// Plain old data that can travel in messages: `f64`, `u64`, `i64`, `u32`,
/// `i32`, `u8` and `usize` (sent as the unsigned integer of the same width).
///
/// The trait is sealed: other crates pack their data into these types (for
/// example particle fields as `f64`, keys as `u64`).
pub trait Plain:
    sealed::Sealed + Copy + Default + PartialEq + Debug + Send + Sync + 'static
{
}

macro_rules! impl_plain {
    ($($t:ty),*) => {$(
        impl sealed::Sealed for $t {}
        impl Plain for $t {}
    )*};
}
impl_plain!(f64, u64, i64, u32, i32, u8, usize);

/// The reduction applied by [`crate::Communicator::all_reduce`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ReduceOp {
    /// Sum of the values of all ranks. For `f64` the result depends on the
    /// rank count (rounding); use [`crate::ExactSum`] when it must not.
    Sum,
    /// Minimum over all ranks.
    Min,
    /// Maximum over all ranks.
    Max,
}

/// Element types of all-reductions: `f64`, `u64`, `i64` and `usize`.
pub trait Reducible: Plain + sealed::SealedReduce {}

macro_rules! impl_reducible {
    ($($t:ty => $sum:expr),*) => {$(
        impl sealed::SealedReduce for $t {
            #[inline]
            fn combine(a: Self, b: Self, op: ReduceOp) -> Self {
                match op {
                    ReduceOp::Sum => $sum(a, b),
                    ReduceOp::Min => if b < a { b } else { a },
                    ReduceOp::Max => if b > a { b } else { a },
                }
            }
        }
        impl Reducible for $t {}
    )*};
}
impl_reducible!(
    f64 => <f64 as std::ops::Add>::add,
    u64 => u64::wrapping_add,
    i64 => i64::wrapping_add,
    usize => usize::wrapping_add
);
