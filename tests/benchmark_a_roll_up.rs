//! BENCHMARKS.md case A (Sze, Liu & Lo 2004, case 3.2): a cantilever strip
//! rolled up by an end moment. L = 12, b = 1, h = 0.1, E = 1.2e6, nu = 0
//! (EI = 100), clamped at x = 0; M_max = 2 pi EI / L rolls it into a full
//! circle. Exact tip: -u = L (1 - sin t / t), w = L (1 - cos t) / t, t = M L / EI.
//! Meshes split every cell along one diagonal direction (three-direction
//! meshes), 12-point rule; tolerance 1 % of each exact value (w at the full
//! circle is 0: compared against 1 % of L). The problem set-up is
//! `origami_fmu::benchmarks::RollUp`, shared with `benches/roll_up_convergence.rs`.
//!
//! Measured here, and why the full circle uses a finer mesh and the planar
//! restraint:
//! - 16 x 1 cells lock in membrane at M/M_max = 0.75 (w off 11 %; the error
//!   grows as the strip gets thinner at the same EI); 64 x 1 cells are
//!   within 0.7 %.
//! - The free 3D strip turns sideways under this moment (the projected
//!   angle gives the end tilt about x the stiffness M sin(psi) cos(psi),
//!   negative for psi in (pi/2, pi) and (3 pi/2, 2 pi)); on 64 x 1 cells the
//!   load path ends in a limit point near M/M_max = 0.885 that no increment
//!   passes. The exact solution is a cylinder, dr/dY = e_y everywhere, so
//!   holding those gradient slots poses the benchmark's planar problem.
//! - On "union-jack" meshes (alternating diagonals) the BCIZ-type element
//!   does not converge (`union_jack_mesh_does_not_converge`).

use origami_fmu::benchmarks::{ROLL_UP_L, RollUp, roll_up_exact};

/// Assert that each point is within 1 % of the exact tip (w at the full
/// circle within 1 % of L).
fn check_within_one_percent(case: RollUp, ratios: &[f64]) {
    let run = case.solve(ratios).unwrap();
    assert_eq!(run.points.len(), ratios.len());
    for p in &run.points {
        let (ue, we) = roll_up_exact(p.ratio);
        eprintln!(
            "{} x {} cells, M/Mmax {}: -u {:.4} (exact {ue:.4}), w {:.4} (exact {we:.4}), {} iterations",
            case.nx, case.ny, p.ratio, p.u, p.w, p.iterations
        );
        assert!((p.u - ue).abs() <= 0.01 * ue, "-u {} vs {ue}", p.u);
        let w_scale = if p.ratio == 1.0 { ROLL_UP_L } else { we };
        assert!((p.w - we).abs() <= 0.01 * w_scale, "w {} vs {we}", p.w);
    }
}

/// The free strip (no planar restraint) on 16 x 1 cells, up to half a turn.
#[test]
fn strip_rolls_up_within_one_percent() {
    let case = RollUp {
        planar: false,
        ..RollUp::new(16)
    };
    check_within_one_percent(case, &[0.25, 0.5]);
}

/// 64 x 1 cells, planar: one load path through 0.25, 0.5, 0.75 and the full
/// circle.
#[test]
fn strip_rolls_into_full_circle() {
    check_within_one_percent(RollUp::new(64), &[0.25, 0.5, 0.75, 1.0]);
}

/// Why the full circle is planar: the free strip drifts sideways by the same
/// amount on 32 and 64 cells (a property of the 3D problem under this
/// moment, not of the mesh), the planar one by much less.
#[test]
fn free_strip_turns_sideways() {
    let lateral = |nx, planar| {
        let case = RollUp {
            planar,
            ..RollUp::new(nx)
        };
        case.solve(&[0.75]).unwrap().points[0].lateral
    };
    let (free32, free64, planar64) = (lateral(32, false), lateral(64, false), lateral(64, true));
    eprintln!(
        "lateral drift at 0.75: free {free32:.3e} (32), {free64:.3e} (64), planar {planar64:.3e}"
    );
    assert!(free32 > 0.1 && free64 > 0.1, "{free32} {free64}");
    assert!((free32 - free64).abs() < 0.05 * free64, "{free32} {free64}");
    assert!(planar64 < 1e-2 * free64, "{planar64}");
}

/// Small moment (linear regime, theta = 0.0126): tip deflection w = M L^2 / (2 EI)
/// within 0.1 % on three-direction meshes of 4, 8 and 16 cells.
#[test]
fn small_moment_linear_rotation() {
    for nx in [4, 8, 16] {
        let ratio = 0.002;
        let case = RollUp {
            planar: false,
            ..RollUp::new(nx)
        };
        let w = case.solve(&[ratio]).unwrap().points[0].w;
        let (_, we) = roll_up_exact(ratio);
        assert!((w - we).abs() < 1e-3 * we, "nx {nx}: w {w} vs {we}");
    }
}

/// Records the known non-convergence on union-jack meshes (alternating
/// diagonals): the error grows under refinement instead of shrinking.
#[test]
fn union_jack_mesh_does_not_converge() {
    let ratio = 0.002;
    let (_, we) = roll_up_exact(ratio);
    let err = |nx| {
        let case = RollUp {
            alternate: true,
            planar: false,
            ..RollUp::new(nx)
        };
        (case.solve(&[ratio]).unwrap().points[0].w - we).abs() / we
    };
    let (e4, e16) = (err(4), err(16));
    assert!(e4 < 2e-3, "coarse union-jack error {e4}");
    assert!(
        e16 > 0.05,
        "if this fails the element now converges on union-jack meshes: update the docs ({e16})"
    );
}
