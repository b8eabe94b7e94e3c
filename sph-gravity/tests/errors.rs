//! Invalid inputs give the documented errors, naming the bad value.

use sph_comm::{CommError, SerialComm};
use sph_gravity::{
    compute_gravity, direct, Decomposition, DistributedGravity, GravityError, GravityField,
    GravityParams, Targets, TreeGravity,
};
use sph_tree::{Boundary, BoundingBox, Curve, Octree, TreeError};

fn params(theta: f64) -> GravityParams {
    GravityParams {
        theta,
        ..GravityParams::default()
    }
}

#[test]
fn bad_parameters() {
    for theta in [0.0, -0.5, f64::NAN, f64::INFINITY] {
        let e = TreeGravity::new(params(theta)).unwrap_err();
        assert!(matches!(e, GravityError::InvalidTheta(_)));
        assert!(e.to_string().contains(&format!("{theta}")), "{e}");
    }
    let e = TreeGravity::new(GravityParams {
        g: f64::NAN,
        ..GravityParams::default()
    })
    .unwrap_err();
    assert!(matches!(e, GravityError::InvalidG(_)));
    let e = TreeGravity::new(GravityParams {
        group_size: 0,
        ..GravityParams::default()
    })
    .unwrap_err();
    assert_eq!(e, GravityError::InvalidGroupSize(0));
    let e = TreeGravity::new(GravityParams {
        leaf_size: 0,
        ..GravityParams::default()
    })
    .unwrap_err();
    assert_eq!(e, GravityError::Tree(TreeError::InvalidBucketSize(0)));
}

#[test]
fn bad_inputs() {
    let p = GravityParams::default();
    let x = [0.0, 1.0, 2.0];
    let e = compute_gravity(&x, &x, &x, &[1.0, 1.0], None, &p).unwrap_err();
    assert_eq!(
        e,
        GravityError::LengthMismatch {
            what: "m",
            len: 2,
            expected: 3
        }
    );
    assert!(e.to_string().contains("m has 2"), "{e}");

    let e = compute_gravity(&x, &[0.0, f64::NAN, 0.0], &x, &[1.0; 3], None, &p).unwrap_err();
    assert!(matches!(
        e,
        GravityError::NonFinite {
            index: 1,
            what: "y",
            ..
        }
    ));
    assert!(e.to_string().contains("NaN"), "{e}");

    let e = compute_gravity(&x, &x, &x, &[1.0; 3], Some(&[0.1, 0.1, -0.2]), &p).unwrap_err();
    assert_eq!(
        e,
        GravityError::NegativeSoftening {
            index: 2,
            value: -0.2
        }
    );
    assert!(e.to_string().contains("-0.2"), "{e}");

    let mut out = GravityField::new();
    let e = direct::direct_sum(&x, &x, &x, &[1.0, f64::INFINITY, 1.0], None, 1.0, &mut out)
        .unwrap_err();
    assert!(matches!(
        e,
        GravityError::NonFinite {
            index: 1,
            what: "m",
            ..
        }
    ));
}

#[test]
fn periodic_box_and_wrong_tree() {
    let x = [0.1, 0.5, 0.9];
    let keys = [1u64 << 10, 1 << 20, 1 << 30];
    let tree = Octree::build(&keys, &x, &x, &x, 1).unwrap();
    let mut solver = TreeGravity::new(GravityParams::default()).unwrap();
    let mut out = GravityField::new();
    let periodic = BoundingBox::new(
        [0.0; 3],
        [1.0; 3],
        [Boundary::Open, Boundary::Periodic, Boundary::Open],
    )
    .unwrap();
    let e = solver
        .compute(&tree, &periodic, &x, &x, &x, &[1.0; 3], None, &mut out)
        .unwrap_err();
    assert_eq!(e, GravityError::PeriodicBox { axis: 1 });
    assert!(e.to_string().contains("Ewald"), "{e}");

    let open = BoundingBox::cube(0.0, 1.0, Boundary::Open).unwrap();
    let e = solver
        .compute(
            &tree,
            &open,
            &x[..2],
            &x[..2],
            &x[..2],
            &[1.0; 2],
            None,
            &mut out,
        )
        .unwrap_err();
    assert_eq!(
        e,
        GravityError::TreeMismatch {
            tree: 3,
            particles: 2
        }
    );
}

#[test]
fn empty_and_single_particle() {
    let p = GravityParams::default();
    let (f, st) = compute_gravity(&[], &[], &[], &[], None, &p).unwrap();
    assert!(f.is_empty());
    assert_eq!(st.interactions_per_particle(), 0.0);
    let (f, st) = compute_gravity(&[1.0], &[2.0], &[3.0], &[5.0], Some(&[0.1]), &p).unwrap();
    assert_eq!(f.acc(0), [0.0; 3]);
    assert_eq!(f.phi[0], 0.0);
    assert_eq!(st.p2p + st.m2p, 0);
}

#[test]
fn decomposition_with_wrong_bound_count() {
    let x = [0.1, 0.5, 0.9];
    let keys = [1u64 << 10, 1 << 20, 1 << 30];
    let tree = Octree::build(&keys, &x, &x, &x, 1).unwrap();
    let bbox = BoundingBox::cube(0.0, 1.0, Boundary::Open).unwrap();
    let mut solver = DistributedGravity::new(GravityParams::default()).unwrap();
    let mut out = GravityField::new();
    let dec = Decomposition {
        bbox: &bbox,
        curve: Curve::Hilbert,
        key_start: &[0, 1 << 20, 1 << 62],
        h_max: 0.0,
    };
    let e = solver
        .compute(
            &SerialComm::new(),
            dec,
            &tree,
            &x,
            &x,
            &x,
            &[1.0; 3],
            None,
            Targets::ALL,
            &mut out,
        )
        .unwrap_err();
    assert_eq!(
        e,
        GravityError::InvalidDecomposition {
            bounds: 3,
            ranks: 1
        }
    );
    assert!(
        e.to_string().contains("3 key-range bounds for 1 ranks"),
        "{e}"
    );
}

#[test]
fn communication_errors_keep_the_comm_error() {
    let inner = CommError::InvalidRank { rank: 5, size: 4 };
    let e = GravityError::from(inner.clone());
    assert_eq!(e, GravityError::Communication(inner.clone()));
    assert_eq!(e.to_string(), inner.to_string());
}

#[test]
fn targets_of_the_wrong_length_or_a_bad_drift() {
    let x = [0.1, 0.5, 0.9];
    let keys = [1u64 << 10, 1 << 20, 1 << 30];
    let tree = Octree::build(&keys, &x, &x, &x, 1).unwrap();
    let bbox = BoundingBox::cube(0.0, 1.0, Boundary::Open).unwrap();
    let mut solver = TreeGravity::new(GravityParams::default()).unwrap();
    let mut out = GravityField::new();
    let mut run = |t: Targets<'_>| {
        solver
            .compute_targets(&tree, &bbox, &x, &x, &x, &[1.0; 3], None, t, &mut out)
            .unwrap_err()
    };
    let two = [true, false];
    assert_eq!(
        run(Targets {
            active: Some(&two),
            drift: 0.0
        }),
        GravityError::TargetMismatch {
            flags: 2,
            particles: 3
        }
    );
    for bad in [-1e-3, f64::NAN, f64::INFINITY] {
        let e = run(Targets {
            active: None,
            drift: bad,
        });
        assert!(matches!(e, GravityError::InvalidDrift(_)), "{e}");
        assert!(e.to_string().contains("drift bound"), "{e}");
    }
}
