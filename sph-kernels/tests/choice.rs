//! `KernelChoice` parsing and display.

use proptest::prelude::*;
use sph_kernels::{Kernel, KernelChoice, KernelError, Sinc};

fn any_choice() -> impl Strategy<Value = KernelChoice> {
    prop_oneof![
        Just(KernelChoice::CubicSpline),
        Just(KernelChoice::WendlandC2),
        Just(KernelChoice::WendlandC4),
        Just(KernelChoice::WendlandC6),
        (Sinc::MIN_EXPONENT..=Sinc::MAX_EXPONENT).prop_map(KernelChoice::Sinc),
        (1u16..=1000).prop_map(|n| KernelChoice::Sinc(n.into())),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn display_parse_round_trip(choice in any_choice()) {
        let text = choice.to_string();
        let back: KernelChoice = text.parse().unwrap();
        prop_assert_eq!(back, choice, "via {:?}", text);
        // Case and surrounding blanks do not matter.
        let shouted: KernelChoice = format!("  {}\t", text.to_uppercase()).parse().unwrap();
        prop_assert_eq!(shouted, choice);
    }

    #[test]
    fn parsing_never_panics(text in "\\PC{0,20}") {
        // Any string is either a valid choice or a described error.
        match text.parse::<KernelChoice>() {
            Ok(choice) => prop_assert!(choice.exact().is_ok()),
            Err(err) => prop_assert!(!err.to_string().is_empty()),
        }
    }

    #[test]
    fn sinc_prefix_with_garbage_names_the_number(garbage in "[a-z#%,]{1,8}") {
        prop_assume!(!["inf", "infinity", "nan"].contains(&garbage.as_str()));
        let input = format!("sinc:{garbage}");
        let err = input.parse::<KernelChoice>().unwrap_err();
        let is_bad_number = matches!(err, KernelError::BadSincNumber { .. });
        prop_assert!(is_bad_number, "{}", err);
        prop_assert!(err.to_string().contains(&format!("\"{garbage}\"")), "{}", err);
    }
}

#[test]
fn default_is_sinc6() {
    assert_eq!(KernelChoice::default(), KernelChoice::Sinc(6.0));
    let exact = KernelChoice::default().exact().unwrap();
    assert_eq!(exact.norm(), Sinc::new(6.0).unwrap().norm());
}

#[test]
fn error_messages_name_the_bad_value() {
    let msg = "wendland-c3"
        .parse::<KernelChoice>()
        .unwrap_err()
        .to_string();
    assert_eq!(
        msg,
        "unknown kernel \"wendland-c3\"; allowed: sinc, sinc:<n>, m4, cubic-spline, \
         wendland-c2, wendland-c4, wendland-c6"
    );
    let msg = "sinc:0.5".parse::<KernelChoice>().unwrap_err().to_string();
    assert_eq!(
        msg,
        "sinc exponent n = 0.5 is out of range: a finite n with 1 <= n <= 1000 is required"
    );
    let msg = "sinc:six".parse::<KernelChoice>().unwrap_err().to_string();
    assert!(
        msg.starts_with("bad sinc exponent \"six\" in \"sinc:six\""),
        "{msg}"
    );
    let msg = KernelChoice::CubicSpline
        .tabulate(0)
        .unwrap_err()
        .to_string();
    assert_eq!(msg, "a kernel table needs at least 2 points, got 0");
}
