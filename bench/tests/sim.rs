//! Throughput of the stepper. Ignored by default (it is a measurement, not a check); run
//! `cargo test --release -p hnav-bench --test sim -- --ignored --nocapture`.

#[test]
#[ignore = "measurement; run in release"]
fn robot_steps_per_second_for_1_64_1024_robots() {
    for n in [1, 64, 1024] {
        let r = hnav_bench::sim::robot_steps_per_second(n, 2.0).unwrap();
        println!(
            "{n:>5} robots: {:.3e} robot-steps/s ({} steps in {:.2} s, {} collisions)",
            r.robot_steps_per_s, r.steps, r.elapsed_s, r.collisions
        );
    }
}
