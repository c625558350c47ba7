//! The element on coarse meshes, as users mesh panels: signed errors of the
//! clamped plate under uniform load (centre deflection), the cantilever
//! plate's modes 1-5 and a square panel clamped on one edge under a tip line
//! load, for the pointwise and split bending energies of Specht's functions
//! and for BCIZ's, on same-diagonal and union-jack meshes.
//! Run with `cargo bench --bench coarse_meshes` (about 30 s; the references
//! are `CANTILEVER_PLATE_MODES` and `PANEL_TIP`, checked by
//! `tests/coarse_meshes.rs`).

use origami_fmu::benchmarks::{
    CANTILEVER_PLATE_MODES, CantileverModes, FamilyStudy, MeshFamily, PANEL_TIP, PanelTip,
};
use origami_fmu::element::{Bending, ElementOptions, Interpolation};

const FAMILIES: [MeshFamily; 2] = [MeshFamily::SameDiagonal, MeshFamily::UnionJack];

fn elements() -> [(&'static str, ElementOptions); 3] {
    let specht = ElementOptions::from(Interpolation::Specht);
    [
        ("Specht, pointwise", specht),
        (
            "Specht, split",
            ElementOptions {
                bending: Bending::Split,
                ..specht
            },
        ),
        ("BCIZ, pointwise", ElementOptions::from(Interpolation::Bciz)),
    ]
}

fn pct(x: f64) -> String {
    format!("{:+.2} %", 100.0 * x)
}

fn main() {
    let cells = [4, 8, 16, 32];
    println!("### Clamped plate, uniform load: centre deflection\n");
    println!("| element | family | 4 x 4 | 8 x 8 | 16 x 16 | 32 x 32 |");
    println!("|---|---|---|---|---|---|");
    for (name, element) in elements() {
        for family in FAMILIES {
            let errs: Vec<String> = cells
                .iter()
                .map(|&n| pct(FamilyStudy::ClampedPlate.error(family, element, n).unwrap()))
                .collect();
            println!("| {name} | {} | {} |", family.name(), errs.join(" | "));
        }
    }

    println!("\n### Cantilever plate: modes 1-5 (omega a^2 sqrt(rho h / D)) against");
    println!(
        "{CANTILEVER_PLATE_MODES:?}\n\n| element | family | cells | mode 1 | 2 | 3 | 4 | 5 | largest |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    for (name, element) in elements() {
        for family in FAMILIES {
            for n in cells {
                let modes = CantileverModes { n, family, element }.solve(5).unwrap();
                let errs: Vec<f64> = modes
                    .iter()
                    .zip(CANTILEVER_PLATE_MODES)
                    .map(|(m, r)| m / r - 1.0)
                    .collect();
                let largest = errs.iter().fold(0.0_f64, |a, e| a.max(e.abs()));
                let cols: Vec<String> = errs.iter().map(|&e| pct(e)).collect();
                println!(
                    "| {name} | {} | {n} x {n} | {} | {} |",
                    family.name(),
                    cols.join(" | "),
                    pct(largest).replace('+', "")
                );
            }
        }
    }

    println!("\n### Square panel clamped on one edge, tip line load: tip deflection");
    println!("against {PANEL_TIP} p a^3 / D\n");
    println!("| element | family | 2 triangles | 8 triangles | 32 | 128 | 2048 |");
    println!("|---|---|---|---|---|---|---|");
    for (name, element) in elements() {
        for family in FAMILIES {
            let errs: Vec<String> = [1, 2, 4, 8, 32]
                .iter()
                .map(|&n| {
                    let tip = PanelTip { n, family, element }.solve().unwrap();
                    pct(tip / PANEL_TIP - 1.0)
                })
                .collect();
            println!("| {name} | {} | {} |", family.name(), errs.join(" | "));
        }
    }
}
