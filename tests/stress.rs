//! The numerical stress suite (src/stress/): every case must count 0 NaN/Inf samples on the device and,
//! where an answer is known (analytic, or the same image as its unstressed twin), reach it.

mod common;

#[test]
fn every_stress_case_is_finite_and_right() {
    let ctx = common::gpu();
    let outcomes = mislab::lab::stress::run(&ctx, None, |o| eprintln!("{}", mislab::lab::stress::progress_line(o)))
        .unwrap_or_else(|e| panic!("the stress suite could not run: {e}"));
    eprintln!("{}", mislab::lab::stress::table(&outcomes));
    assert!(outcomes.len() >= 40, "the issue asks for at least 40 stress configurations, found {}", outcomes.len());
    let analytic = outcomes.iter().filter(|o| o.expected.is_some()).count();
    assert!(analytic >= 30, "at least 30 cases should check a known mean, found {analytic}");
    let failed: Vec<String> =
        outcomes.iter().filter(|o| !o.pass).map(|o| format!("{}: {}", o.name, o.detail)).collect();
    assert!(failed.is_empty(), "{} of {} stress cases failed:\n{}", failed.len(), outcomes.len(), failed.join("\n"));
    assert_eq!(outcomes.iter().map(|o| o.nonfinite).sum::<u64>(), 0);
}
