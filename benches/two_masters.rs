//! How far two FMI masters' runs of the free square drift apart when their
//! communication step sizes differ only in the last bit (fmi-sim passes
//! 0.01 every step; fmpy's simulate_fmu passes differences of
//! communication points, 0.009999999999999998 and the like), with the
//! input ramping over each step as `tests/fmpy/test_second_client.py`
//! builds it. Undamped (the test scene's setting) and with the automatic
//! damping: the largest output difference at each communication point.
//!
//! `cargo bench --bench two_masters`

mod common;

/// Outputs after each of ten 10 ms communication steps, the step sizes
/// either all 0.01 or differences of communication points.
fn run(auto_damping: bool, differences: bool) -> Vec<Vec<f64>> {
    let (mut m, fold) = common::square_model(|mut scene| {
        scene.auto_damping = auto_damping;
        scene
    });
    (0..10)
        .map(|k| {
            let t = k as f64 * 0.01;
            let h = if differences {
                (k + 1) as f64 * 0.01 - t
            } else {
                0.01
            };
            m.set_input(fold, (t / 0.1).min(1.0)).expect("input");
            m.advance(h).expect("advance");
            m.output_values()
        })
        .collect()
}

fn main() {
    println!("| t s | undamped: largest output difference | automatic damping |");
    println!("| --- | --- | --- |");
    let diffs: Vec<Vec<f64>> = [false, true]
        .iter()
        .map(|&damped| {
            let (a, b) = (run(damped, false), run(damped, true));
            a.iter()
                .zip(&b)
                .map(|(x, y)| {
                    x.iter()
                        .zip(y)
                        .map(|(p, q)| (p - q).abs())
                        .fold(0.0, f64::max)
                })
                .collect()
        })
        .collect();
    for (k, (undamped, damped)) in diffs[0].iter().zip(&diffs[1]).enumerate() {
        println!(
            "| {:.2} | {undamped:.1e} | {damped:.1e} |",
            (k + 1) as f64 * 0.01
        );
    }
}
