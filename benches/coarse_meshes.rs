//! The element on coarse meshes, as users mesh panels: signed errors of the
//! clamped plate under uniform load (centre deflection), the cantilever
//! plate's modes 1-5 and a square panel clamped on one edge under a tip line
//! load, for the pointwise and split bending energies of Specht's functions
//! and for BCIZ's, on same-diagonal and union-jack meshes.
//! Then large deflections, both bending energies: a cantilever strip under
//! a tip force (Sze, Liu & Lo's case 3.1, P L^2 / EI = 4) against the
//! elastica, and square plates under pressure with immovable edges, simply
//! supported and clamped, against 32 x 32 cells.
//! Run with `cargo bench --bench coarse_meshes` (about 35 s; the
//! references are `CANTILEVER_PLATE_MODES` and `PANEL_TIP`, checked by
//! `tests/coarse_meshes.rs`).

use origami_fmu::benchmarks::{
    CANTILEVER_PLATE_MODES, CantileverModes, FamilyStudy, MeshFamily, PANEL_TIP, PanelTip,
    Supports, plate_physics, pressure_load, static_deflection,
};
use origami_fmu::element::{Bending, ElementOptions, Interpolation};
use origami_fmu::ids::VertexId;
use origami_fmu::solver::statics::StaticSettings;

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

/// Sixteen load steps, Newton to a relative residual of 1e-8.
const PATH: StaticSettings = StaticSettings {
    load_steps: 16,
    max_iterations: 60,
    tolerance: 1e-8,
    min_increment: 1e-6,
};

fn with_bending(bending: Bending) -> ElementOptions {
    ElementOptions {
        bending,
        ..ElementOptions::default()
    }
}

/// The tip `(-u, w) / L` of the inextensible cantilever (elastica) under a
/// tip force `k = P L^2 / EI` normal to it: `theta' = m`, `m' = -k cos theta`,
/// `theta(0) = 0`, `m(1) = 0`, shot on `m(0)` (RK4, 4000 steps).
fn elastica(k: f64) -> (f64, f64) {
    let run = |m0: f64| {
        let n = 4000;
        let h = 1.0 / n as f64;
        let f = |s: [f64; 4]| [s[1], -k * s[0].cos(), s[0].cos(), s[0].sin()];
        let mut s = [0.0, m0, 0.0, 0.0];
        for _ in 0..n {
            let add = |a: [f64; 4], b: [f64; 4], t: f64| std::array::from_fn(|i| a[i] + t * b[i]);
            let k1 = f(s);
            let k2 = f(add(s, k1, 0.5 * h));
            let k3 = f(add(s, k2, 0.5 * h));
            let k4 = f(add(s, k3, h));
            s = std::array::from_fn(|i| {
                s[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])
            });
        }
        s
    };
    let (mut lo, mut hi) = (0.0, k);
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if run(mid)[1] > 0.0 {
            hi = mid
        } else {
            lo = mid
        }
    }
    let s = run(0.5 * (lo + hi));
    (1.0 - s[2], s[3])
}

/// Sze 3.1's strip (L = 10, b = 1, h = 0.1, E = 1.2e6, nu = 0) clamped at
/// x = 0 under the tip force `k EI / L^2` shared by the tip vertices
/// (trapezoidal): the tip's mean w / L.
fn cantilever(nx: usize, ny: usize, family: MeshFamily, bending: Bending, k: f64) -> f64 {
    let (l, b, h, e) = (10.0, 1.0, 0.1, 1.2e6);
    let ei = e * b * h * h * h / 12.0;
    let mesh = family.grid(l, b, nx, ny);
    let at = |x: f64| -> Vec<VertexId> {
        mesh.vertex_ids()
            .filter(|&v| (mesh.coord(v).x - x).abs() < 1e-12)
            .collect()
    };
    let (root, tips) = (at(0.0), at(l));
    let p = k * ei / (l * l);
    let (w, _) = static_deflection(
        &mesh,
        plate_physics(e, 0.0, h),
        with_bending(bending),
        Supports {
            vertices: &root,
            clamped: true,
        },
        |asm| {
            let mut f = vec![0.0; asm.n_dofs()];
            for &v in &tips {
                let y = mesh.coord(v).y;
                let share = if y == 0.0 || y == b { 0.5 } else { 1.0 } / ny as f64;
                f[3 * asm.position_slot(v) + 2] = p * share;
            }
            f
        },
        &tips,
        PATH,
    )
    .unwrap();
    w / l
}

/// A square plate (a = 1, h = 0.01, E = 1e7, nu = 0.3), every boundary
/// vertex's position held (clamped: every slot), under the pressure
/// `Q E h^4 / a^4`: the centre's w / h.
fn plate(n: usize, family: MeshFamily, bending: Bending, clamped: bool, load: f64) -> f64 {
    let (a, e, nu, h): (f64, f64, f64, f64) = (1.0, 1.0e7, 0.3, 0.01);
    let mesh = family.grid(a, a, n, n);
    let on_edge = |x: f64| x.abs() < 1e-12 || (x - a).abs() < 1e-12;
    let boundary: Vec<VertexId> = mesh
        .vertex_ids()
        .filter(|&v| on_edge(mesh.coord(v).x) || on_edge(mesh.coord(v).y))
        .collect();
    let centre = VertexId((n / 2) * (n + 1) + n / 2);
    let q = load * e * h.powi(4) / a.powi(4);
    let (w, _) = static_deflection(
        &mesh,
        plate_physics(e, nu, h),
        with_bending(bending),
        Supports {
            vertices: &boundary,
            clamped,
        },
        |asm| pressure_load(asm, q, h),
        &[centre],
        PATH,
    )
    .unwrap();
    w / h
}

fn large_deflections() {
    let energies = [Bending::Pointwise, Bending::Split];
    let (u, w) = elastica(4.0);
    println!("\n### Cantilever strip, tip force P L^2 / EI = 4 (Sze 3.1): tip w / L");
    println!("against the elastica's {w:.5} (-u / L {u:.5})\n");
    println!("| family | bending | 4 x 1 | 8 x 1 | 16 x 1 | 10 x 2 | 20 x 2 |");
    println!("|---|---|---|---|---|---|---|");
    for family in FAMILIES {
        for bending in energies {
            let errs: Vec<String> = [(4, 1), (8, 1), (16, 1), (10, 2), (20, 2)]
                .iter()
                .map(|&(nx, ny)| pct(cantilever(nx, ny, family, bending, 4.0) / w - 1.0))
                .collect();
            println!("| {} | {bending:?} | {} |", family.name(), errs.join(" | "));
        }
    }
    println!("\n### Square plates under pressure Q = q a^4 / (E h^4), immovable edges:");
    println!("centre w / h against 32 x 32 same-diagonal cells of the split energy\n");
    println!("| edges | Q | w / h (32 x 32) | family | bending | 4 x 4 | 8 x 8 | 16 x 16 |");
    println!("|---|---|---|---|---|---|---|---|");
    for clamped in [false, true] {
        for load in [50.0, 250.0] {
            let reference = plate(32, MeshFamily::SameDiagonal, Bending::Split, clamped, load);
            for family in FAMILIES {
                for bending in energies {
                    let errs: Vec<String> = [4, 8, 16]
                        .iter()
                        .map(|&n| pct(plate(n, family, bending, clamped, load) / reference - 1.0))
                        .collect();
                    println!(
                        "| {} | {load} | {reference:.5} | {} | {bending:?} | {} |",
                        if clamped { "clamped" } else { "pinned" },
                        family.name(),
                        errs.join(" | ")
                    );
                }
            }
        }
    }
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
    large_deflections();
}
