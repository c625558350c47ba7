//! The shell element on four mesh families (same diagonal, union-jack,
//! random diagonals, perturbed vertices) for both shape functions and, with
//! Specht's, both bending energies (pointwise, split): signed
//! errors of case A (end moment: small, and half a turn) and case B (tip
//! force on a strip, clamped plate under uniform load) under refinement,
//! and the observed order between the second and the last mesh. First, the
//! cost per element of building it, of force and of force plus tangent.
//! Run with `cargo bench --bench element_families`.

use nalgebra::{SMatrix, SVector, Vector3};
use origami_fmu::benchmarks::{BenchmarkError, FamilyStudy, MeshFamily, plate_physics};
use origami_fmu::element::{
    Bending, ElemVec, ElementOptions, Interpolation, ShellElement, reference_vector,
};
// Times are CPU time (this thread's clock; the benches run on one thread).
use origami_fmu::cpu_time::CpuInstant as Instant;

/// Best-of-`repeats` time of `f` in seconds (the machine is shared).
fn best(repeats: usize, mut f: impl FnMut()) -> f64 {
    (0..repeats)
        .map(|_| {
            let t = Instant::now();
            f();
            t.elapsed().as_secs_f64()
        })
        .fold(f64::INFINITY, f64::min)
}

/// Nanoseconds per element: construction, force, force + tangent, on the
/// facets of a 32 x 32 perturbed grid with a smooth deformation.
fn cost_table() {
    let mesh = MeshFamily::Perturbed.grid(1.0, 1.0, 32, 32);
    let mat = plate_physics(1e7, 0.3, 0.01).material;
    let corners: Vec<_> = mesh
        .triangles()
        .iter()
        .map(|t| t.map(|v| mesh.coord(v)))
        .collect();
    let deformed: Vec<ElemVec> = corners
        .iter()
        .map(|x| {
            reference_vector(x).map(|v| v + Vector3::new(0.01 * v.y, -0.02 * v.x, 0.05 * v.x * v.y))
        })
        .collect();
    let n = corners.len() as f64;
    println!(
        "### Cost per element ({} facets, best of 20, ns)\n",
        corners.len()
    );
    println!(
        "| element | build (CPU ns) | force (CPU ns) | force + tangent (CPU ns) | force + tangent vs BCIZ |"
    );
    println!("|---|---|---|---|---|");
    let mut bciz = f64::NAN;
    for (name, options) in elements() {
        let build = best(20, || {
            for x in &corners {
                std::hint::black_box(ShellElement::with_options(*x, options).unwrap());
            }
        });
        let els: Vec<ShellElement> = corners
            .iter()
            .map(|x| {
                let mut el = ShellElement::with_options(*x, options).unwrap();
                el.prepare(&mat);
                el
            })
            .collect();
        let mut f = SVector::<f64, 27>::zeros();
        let mut k = SMatrix::<f64, 27, 27>::zeros();
        let force = best(20, || {
            for (el, e) in els.iter().zip(&deformed) {
                std::hint::black_box(el.eval(&mat, e, &mut f, None));
            }
        });
        let tangent = best(20, || {
            for (el, e) in els.iter().zip(&deformed) {
                std::hint::black_box(el.eval(&mat, e, &mut f, Some(&mut k)));
            }
        });
        if options.interpolation == Interpolation::Bciz {
            bciz = tangent;
        }
        println!(
            "| {name} | {:.0} | {:.0} | {:.0} | {:.2} |",
            1e9 * build / n,
            1e9 * force / n,
            1e9 * tangent / n,
            tangent / bciz
        );
    }
}

/// The elements compared: BCIZ's and Specht's functions with the pointwise
/// bending energy, Specht's with the split one.
fn elements() -> [(&'static str, ElementOptions); 3] {
    let specht = ElementOptions::from(Interpolation::Specht);
    [
        ("BCIZ", ElementOptions::from(Interpolation::Bciz)),
        ("Specht", specht),
        (
            "Specht, split",
            ElementOptions {
                bending: Bending::Split,
                ..specht
            },
        ),
    ]
}

fn main() {
    cost_table();
    for study in FamilyStudy::ALL {
        let meshes: &[usize] = match study {
            FamilyStudy::ClampedPlate => &[4, 8, 16, 32, 64],
            _ => &[8, 16, 32, 64],
        };
        println!("\n### {}\n", study.name());
        let head: Vec<String> = meshes.iter().map(|n| format!("n = {n}")).collect();
        let (first, last) = (meshes[1], meshes[meshes.len() - 1]);
        println!(
            "| family | element | {} | order {first}-{last} |",
            head.join(" | ")
        );
        println!("|---|---|{}---|", "---|".repeat(meshes.len()));
        for family in MeshFamily::ALL {
            for (name, options) in elements() {
                let errs: Vec<Result<f64, BenchmarkError>> = meshes
                    .iter()
                    .map(|&n| study.error(family, options, n))
                    .collect();
                let cells: Vec<String> = errs
                    .iter()
                    .map(|e| match e {
                        Ok(x) => format!("{x:+.2e}"),
                        Err(m) => {
                            eprintln!("{} {family:?} {name}: {m}", study.name());
                            "failed".into()
                        }
                    })
                    .collect();
                let order = match (&errs[1], &errs[errs.len() - 1]) {
                    (Ok(a), Ok(b)) if *a != 0.0 && *b != 0.0 => {
                        let ratio = (last / first) as f64;
                        format!("{:.2}", (a.abs() / b.abs()).ln() / ratio.ln())
                    }
                    _ => String::new(),
                };
                println!(
                    "| {} | {name} | {} | {order} |",
                    family.name(),
                    cells.join(" | ")
                );
            }
        }
    }
}
