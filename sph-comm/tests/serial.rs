//! Property tests of `SerialComm`: reductions, exchange to self, all-to-all-v
//! and all-gather round trips, argument errors.

use proptest::prelude::*;
use sph_comm::{CommError, Communicator, ReduceOp, SerialComm};

proptest! {
    #[test]
    fn reductions_are_identity(
        f in prop::collection::vec(any::<f64>(), 0..20),
        u in prop::collection::vec(any::<u64>(), 0..20),
        i in prop::collection::vec(any::<i64>(), 0..20),
    ) {
        let comm = SerialComm::new();
        for op in [ReduceOp::Sum, ReduceOp::Min, ReduceOp::Max] {
            let mut f2 = f.clone();
            comm.all_reduce(&mut f2, op);
            prop_assert_eq!(
                f2.iter().map(|x| x.to_bits()).collect::<Vec<_>>(),
                f.iter().map(|x| x.to_bits()).collect::<Vec<_>>()
            );
            let mut u2 = u.clone();
            comm.all_reduce(&mut u2, op);
            prop_assert_eq!(&u2, &u);
            let mut i2 = i.clone();
            comm.all_reduce(&mut i2, op);
            prop_assert_eq!(&i2, &i);
        }
        if let Some(&x) = u.first() {
            prop_assert_eq!(comm.all_reduce_scalar(x, ReduceOp::Sum), x);
        }
    }

    #[test]
    fn exchange_to_self_round_trips(msgs in prop::collection::vec(prop::collection::vec(any::<u64>(), 0..10), 0..6)) {
        let comm = SerialComm::new();
        let sends: Vec<(usize, Vec<u64>)> = msgs.iter().map(|m| (0, m.clone())).collect();
        let got = comm.sparse_exchange(&sends).unwrap();
        prop_assert_eq!(got, sends.clone());
        // Slices work as well as vectors.
        let slices: Vec<(usize, &[u64])> = msgs.iter().map(|m| (0, m.as_slice())).collect();
        prop_assert_eq!(comm.sparse_exchange(&slices).unwrap(), sends);
    }

    #[test]
    fn all_to_all_v_round_trips(data in prop::collection::vec(any::<f64>(), 0..50)) {
        let comm = SerialComm::new();
        let g = comm.all_to_all_v(&data, &[data.len()]).unwrap();
        prop_assert_eq!(&g.counts, &vec![data.len()]);
        prop_assert_eq!(g.from_rank(0).len(), data.len());
        prop_assert!(g.data.iter().zip(&data).all(|(a, b)| a.to_bits() == b.to_bits()));
        let back = comm.all_to_all_v(&g.data, &g.counts).unwrap();
        prop_assert!(back.data.iter().zip(&data).all(|(a, b)| a.to_bits() == b.to_bits()));
    }

    #[test]
    fn all_gather_v_round_trips(data in prop::collection::vec(any::<u8>(), 0..50)) {
        let comm = SerialComm::new();
        let g = comm.all_gather_v(&data).unwrap();
        prop_assert_eq!(g.data, data.clone());
        prop_assert_eq!(g.counts, vec![data.len()]);
        prop_assert_eq!(comm.all_gather_scalar(7usize), vec![7]);
    }
}

#[test]
fn argument_errors() {
    let comm = SerialComm::new();
    assert_eq!(comm.rank(), 0);
    assert_eq!(comm.size(), 1);
    comm.barrier();
    assert_eq!(
        comm.sparse_exchange(&[(0, vec![1u32]), (1, vec![2u32])]),
        Err(CommError::InvalidRank { rank: 1, size: 1 })
    );
    assert_eq!(
        comm.all_to_all_v(&[1i32, 2], &[1, 1]),
        Err(CommError::CountsLength {
            expected: 1,
            got: 2
        })
    );
    assert_eq!(
        comm.all_to_all_v(&[1i64, 2], &[3]),
        Err(CommError::CountsSum {
            counts_sum: 3,
            data_len: 2
        })
    );
    let e = CommError::InvalidRank { rank: 5, size: 4 };
    assert_eq!(
        e.to_string(),
        "rank 5 is out of range for a communicator of size 4"
    );
}

#[test]
fn references_are_communicators() {
    fn total<C: Communicator>(c: C) -> u64 {
        c.all_reduce_scalar(3u64, ReduceOp::Sum) + c.size() as u64
    }
    let comm = SerialComm::new();
    let by_ref: &SerialComm = &comm;
    let by_ref_ref: &&SerialComm = &by_ref;
    assert_eq!(total(by_ref), 4);
    assert_eq!(total(by_ref_ref), 4);
}

#[test]
fn empty_exchange() {
    let comm = SerialComm::new();
    let sends: [(usize, Vec<f64>); 0] = [];
    assert!(comm.sparse_exchange(&sends).unwrap().is_empty());
    let g = comm.all_to_all_v::<f64>(&[], &[0]).unwrap();
    assert!(g.data.is_empty());
}
