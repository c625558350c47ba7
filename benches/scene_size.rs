//! Scene set-up against pattern size: the time of what `origami-fmu check`
//! and `origami-fmu build` do (read the FOLD text, build the scene, build
//! the model; build also writes the FMU description, which rebuilds the
//! model), on Miura-ori sheets from 2k to 131k facets, and the time to
//! refuse a 1,000,000-facet pattern (above the size budget
//! `scene::build::MAX_FACETS`). Near-linear set-up shows as a constant
//! time per facet.
//!
//! `cargo bench --bench scene_size -- [--max 128]` (the largest Miura
//! size n, n x n cells, 8 n^2 facets; 128 is 131,072 facets)

use origami_fmu::fmi;
use origami_fmu::model::Model;
use origami_fmu::scene::{self, patterns::Miura};
// Times are CPU time (this thread's clock; the benches run on one thread).
use origami_fmu::cpu_time::CpuInstant as Instant;

use origami_fmu::benchmarks::arg;

fn main() {
    let max = arg("--max", 128);
    println!(
        "| Miura n x n | facets | DOFs | read + scene CPU s | model CPU s | check CPU s | FMU description CPU s | build CPU s |"
    );
    println!("| --- | --- | --- | --- | --- | --- | --- | --- |");
    let mut n = 16;
    while n <= max {
        let text = Miura {
            nx: n,
            ny: n,
            ..Default::default()
        }
        .generate()
        .expect("valid")
        .to_json();
        let t = Instant::now();
        let (s, _) = scene::from_str(&text).expect("loads");
        let t_scene = t.elapsed().as_secs_f64();
        let facets = s.mesh.triangles().len();
        let t = Instant::now();
        let m = Model::new(s.clone()).expect("model");
        let t_model = t.elapsed().as_secs_f64();
        let dofs = m.n_dofs();
        drop(m);
        let t = Instant::now();
        let c = fmi::fmu_contents(&s).expect("FMU contents");
        let t_fmu = t.elapsed().as_secs_f64();
        drop(c);
        println!(
            "| {n} x {n} | {facets} | {dofs} | {t_scene:.2} | {t_model:.2} | {:.2} | {t_fmu:.2} | {:.2} |",
            t_scene + t_model,
            t_scene + t_fmu
        );
        n *= 2;
    }
    let n = 708;
    let text = origami_fmu::benchmarks::unit_grid_fold(n).to_json();
    let t = Instant::now();
    let e = scene::from_str(&text).expect_err("over the budget");
    println!(
        "\n{} facets refused in {:.2} s (budget {}): {e}",
        2 * n * n,
        t.elapsed().as_secs_f64(),
        scene::build::MAX_FACETS
    );
}
