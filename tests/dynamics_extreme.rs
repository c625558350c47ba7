//! Issue #4, the stiff and extreme suite: each case runs the plain `Model`
//! API where the physics or the numbers are hard, and passes when there is
//! no NaN and no divergence, the energy stays bounded (non-increasing while
//! the inputs are held in a damped run), and the final state is within a
//! stated tolerance of its reference. Every case prints one row with the
//! step controller's work (`--nocapture`); docs/validation.md "Stiff and extreme cases"
//! tabulates them.
//!
//! Reference of the folding cases: with no load but the crease's own rest
//! angle, the static end state is stress free: the clamped panel stays flat
//! and the free panel is turned rigidly about the crease by exactly the
//! target angle (valley positive: lifted towards +z).

mod common;

use common::*;
use nalgebra::{Vector2, Vector3};
use origami_fmu::ids::{VertexId, vertex_ids};
use origami_fmu::mesh::{Edge, Mesh};
use origami_fmu::model::Model;
use origami_fmu::scene::{CreaseStiffness, Scene};
use std::f64::consts::PI;
use std::time::Instant;

/// Panel width (m) of the two-panel scenes.
const W: f64 = 0.02;

/// What a run did: the controller's work and the largest rise of the total
/// energy between samples while the inputs were held (relative to the
/// energy when the hold began).
#[derive(Default)]
struct Run {
    work: Work,
    held_rise: f64,
}

/// Drive the `fold` input of `m` piecewise linearly from its value now
/// through the `(time, value)` points (value and slope set before each
/// step, as a master with input derivatives does), sampling every `dt` (at most), and
/// check every sample for NaN; the work is added to `run`. A segment with
/// equal end values is a hold: its energy rises are recorded in
/// [`Run::held_rise`] for the caller to assert.
fn drive(m: &mut Model, run: &mut Run, points: &[(f64, f64)], dt: f64) {
    let fold = input(m, "fold");
    let (mut t0, mut u0) = (m.time(), m.input(fold).unwrap());
    for &(t1, u1) in points {
        let e_hold = total_energy(m);
        let mut e_prev = e_hold;
        while m.time() < t1 - 1e-12 * t1 {
            let h = dt.min(t1 - m.time());
            // The piecewise linear signal: its value at the step start and
            // its slope over the step.
            let u = u0 + (u1 - u0) * ((m.time() - t0) / (t1 - t0)).min(1.0);
            m.set_input(fold, u).unwrap();
            m.set_input_derivative(fold, 1, (u1 - u0) / (t1 - t0))
                .unwrap();
            run.work.advance(m, h);
            assert!(
                m.output_values().iter().all(|x| x.is_finite()),
                "non-finite output at t = {}",
                m.time()
            );
            let e = total_energy(m);
            if u1 == u0 && e_hold > 0.0 {
                run.held_rise = run.held_rise.max((e - e_prev) / e_hold);
            }
            e_prev = e;
        }
        (t0, u0) = (t1, u1);
    }
}

/// Largest distance, over the free panel's outer vertices (2 and 5), from
/// the rigid rotation of the flat panel by `phi` about the crease at x = w,
/// relative to w.
fn panel_error(m: &Model, w: f64, phi: f64) -> f64 {
    [2, 5]
        .iter()
        .map(|&v| {
            let y = m.scene().mesh.coords()[v].y;
            let want = Vector3::new(w + w * phi.cos(), y, w * phi.sin());
            (Vector3::from(m.vertex_position(VertexId(v))) - want).norm() / w
        })
        .fold(0.0, f64::max)
}

/// The hinge period (s) of the two-panel scene: 2 pi / omega with the rigid
/// panel's omega.
fn hinge_period(scene: &Scene, w: f64) -> f64 {
    2.0 * PI / hinge_omega(scene, w)
}

/// Print one table row: case, what was run, the controller's work, what
/// happened, the runtime.
fn row(case: &str, what: &str, work: &Work, result: &str, clock: Instant) {
    println!(
        "E | {case} | {what} | {} | {result} | {:.2} s",
        work.line(),
        clock.elapsed().as_secs_f64()
    );
}

/// Print a folding case's row and assert its end state: angle within 1e-4
/// rad of `target`, free panel within 1e-4 w of the rigid fold, no energy
/// rise during holds. `note` opens the result column. Returns the angle error.
#[allow(clippy::too_many_arguments)]
fn check_end(
    case: &str,
    what: &str,
    note: &str,
    m: &Model,
    w: f64,
    target: f64,
    run: &Run,
    clock: Instant,
) -> f64 {
    let angle_err = (crease_angle(m) - target).abs();
    let panel_err = panel_error(m, w, target);
    row(
        case,
        what,
        &run.work,
        &format!(
            "{note}angle error {angle_err:.1e} rad, panel error {panel_err:.1e} w, held energy rise {:.0e}",
            run.held_rise
        ),
        clock,
    );
    assert!(angle_err < 1e-4, "{case}: angle error {angle_err}");
    assert!(panel_err < 1e-4, "{case}: panel error {panel_err}");
    assert!(
        run.held_rise < 1e-6,
        "{case}: energy rose {}",
        run.held_rise
    );
    angle_err
}

/// One folding case: with max_step T/20, fold `scene` (two panels of width
/// `w`) to `target` over 2 T, hold 10 T, then [`check_end`].
fn fold_case(case: &str, mut scene: Scene, w: f64, target: f64, t: f64) {
    let clock = Instant::now();
    let integrator = scene.solver.integrator;
    scene.solver.max_step = t / 20.0;
    let mut m = Model::new(scene).unwrap();
    m.initialize().unwrap();
    let mut run = Run::default();
    drive(
        &mut m,
        &mut run,
        &[(2.0 * t, 1.0), (12.0 * t, 1.0)],
        t / 10.0,
    );
    let what = format!(
        "{integrator:?}, fold to {:.0} deg over 2 T (T = {t:.3e} s), hold 10 T",
        target.to_degrees()
    );
    check_end(case, &what, "", &m, w, target, &run, clock);
}

/// Thickness ratios h/L = 1e-2 .. 1e-5 (20 mm paper panels, crease length
/// scale 10 mm, automatic damping): folding to 90 degrees over two hinge
/// periods and holding 10 ends within 1e-4 rad of the target, the free panel
/// within 1e-4 w of its rigid position. The hinge period grows as 1/h, so
/// times and the largest step are in hinge periods (max_step T/20).
#[test]
fn thickness_ratios() {
    let target = PI / 2.0;
    for &integrator in INTEGRATORS {
        for ratio in [1e-2, 1e-3, 1e-4, 1e-5] {
            let mut scene = two_panels(W, target, integrator);
            scene.material.thickness = ratio * W;
            let t = hinge_period(&scene, W);
            fold_case(&format!("thickness h/L = {ratio:.0e}"), scene, W, target, t);
        }
    }
}

/// The thin sheets of [`thickness_ratios`] at loose tolerances 3e-3 ..
/// 1e-1: Newton's tolerance follows the error tolerance only as far as
/// the sheet's thickness allows (`NEWTON_THICKNESS_RATIO`); without that
/// bound these folds end off by up to 1.5 w with the held energy rising
/// 20-fold.
#[test]
fn thin_sheets_at_loose_tolerances() {
    let target = PI / 2.0;
    for tolerance in [3e-3, 3e-2, 1e-1] {
        for ratio in [1e-4, 1e-5] {
            let mut scene = two_panels(W, target, INTEGRATORS[0]);
            scene.material.thickness = ratio * W;
            scene.solver.tolerance = tolerance;
            let t = hinge_period(&scene, W);
            let case = format!("thickness h/L = {ratio:.0e}, tolerance {tolerance:.0e}");
            fold_case(&case, scene, W, target, t);
        }
    }
}

/// Crease-to-bending stiffness ratios k w / D = 1e-4 .. 1e4 (20 mm paper
/// panels, automatic damping): folding to 90 degrees ends within 1e-4 rad
/// of the target and the free panel within 1e-4 w of its rigid position.
/// A soft crease folds slowly (hinge period T); a stiff one snaps the crease
/// at once and the sheet's own bending mode (both panels as one strip of
/// length 2 w clamped at one end, over-damped by the automatic damping tuned
/// to the hinge) then creeps to the end state with the time constant
/// alpha / omega_b^2: the run is scaled by the slower of the two.
#[test]
fn crease_to_bending_ratios() {
    let target = PI / 2.0;
    for &integrator in INTEGRATORS {
        for ratio in [1e-4, 1e-2, 1.0, 1e2, 1e4] {
            let mut scene = two_panels(W, target, integrator);
            crease_ratio(&mut scene, W, ratio);
            // Sheet bending: a clamped strip of length 2 w, 1.875^2 sqrt(D / (rho h (2 w)^4)).
            let mt = scene.material;
            let omega_b = 1.875f64.powi(2)
                * (mt.bending_stiffness() / (mt.density * mt.thickness * (2.0 * W).powi(4))).sqrt();
            let creep = 0.4 * hinge_omega(&scene, W) / omega_b.powi(2);
            let t = hinge_period(&scene, W).max(2.0 * PI * creep);
            fold_case(
                &format!("crease k w / D = {ratio:.0e}"),
                scene,
                W,
                target,
                t,
            );
        }
    }
}

/// Folding through the flat state and to +-179 degrees (default paper
/// panels and crease): 0 -> +179 deg -> -179 deg -> 0, each ramp over 2
/// hinge periods T and each hold 10 T; at the end of every hold the angle is
/// within 1e-4 rad of its target and the free panel within 1e-4 w of its
/// rigid position (179 degrees: the panels nearly face each other; there is
/// no contact model).
#[test]
fn fold_through_flat_to_179_degrees() {
    let full = 179f64.to_radians();
    for &integrator in INTEGRATORS {
        let clock = Instant::now();
        let mut scene = two_panels(W, full, integrator);
        let t = hinge_period(&scene, W);
        scene.solver.max_step = t / 20.0;
        let mut m = Model::new(scene).unwrap();
        m.initialize().unwrap();
        let mut run = Run::default();
        let mut worst = (0.0f64, 0.0f64);
        for (k, u) in [1.0, -1.0, 0.0].into_iter().enumerate() {
            let t0 = 12.0 * t * k as f64;
            let points = [(t0 + 2.0 * t, u), (t0 + 12.0 * t, u)];
            drive(&mut m, &mut run, &points, t / 10.0);
            let (angle_err, panel_err) = (
                (crease_angle(&m) - u * full).abs(),
                panel_error(&m, W, u * full),
            );
            println!("  u = {u}: angle error {angle_err:.1e}, panel error {panel_err:.1e}");
            assert!(angle_err < 1e-4, "u {u}: angle error {angle_err}");
            assert!(panel_err < 1e-4, "u {u}: panel error {panel_err}");
            worst = (worst.0.max(angle_err), worst.1.max(panel_err));
        }
        let rise = run.held_rise;
        row(
            "fold through flat to +-179 deg",
            &format!(
                "{integrator:?}, 0 -> +179 -> -179 -> 0 deg, ramps 2 T, holds 10 T (T = {t:.3e} s)"
            ),
            &run.work,
            &format!(
                "worst angle error {:.1e} rad, panel error {:.1e} w, held energy rise {rise:.0e}",
                worst.0, worst.1
            ),
            clock,
        );
        assert!(rise < 1e-6, "energy rose {rise}");
    }
}

/// A near-degenerate triangle: the free panel of the two-panel scene is
/// split around a vertex 1e-3 w from its free edge, so one facet has the
/// aspect ratio 1e3 (edge w, height w / 1000). Folding to 90 degrees ends
/// within 1e-4 rad and 1e-4 w of the rigid state, as on the regular mesh.
#[test]
fn near_degenerate_triangle() {
    let target = PI / 2.0;
    let (w, d) = (W, W * 1e-3);
    let v = |x: f64, y: f64| Vector2::new(x, y);
    // 0 1 2 along y = 0, 3 4 5 along y = w, 6 inside near the edge 2-5.
    let coords = vec![
        v(0.0, 0.0),
        v(w, 0.0),
        v(2.0 * w, 0.0),
        v(0.0, w),
        v(w, w),
        v(2.0 * w, w),
        v(2.0 * w - d, 0.5 * w),
    ];
    let tris = vec![
        [0, 1, 4],
        [0, 4, 3],
        [1, 2, 6],
        [2, 5, 6],
        [5, 4, 6],
        [4, 1, 6],
    ];
    let tris = tris.into_iter().map(vertex_ids).collect();
    let crease = Edge::crease(VertexId(1), VertexId(4), target);
    let mesh = Mesh::new(coords, tris, vec![crease]).unwrap();
    let (a, b) = (
        mesh.coords()[5] - mesh.coords()[2],
        mesh.coords()[6] - mesh.coords()[2],
    );
    let aspect = a.norm().powi(2) / (a.x * b.y - a.y * b.x).abs();
    assert!((aspect - 1e3).abs() < 1.0, "aspect ratio {aspect}");
    for &integrator in INTEGRATORS {
        let mut scene = Scene::with_defaults("sliver", mesh.clone());
        scene.supports = two_panels(w, target, integrator).supports;
        scene.solver.integrator = integrator;
        let t = hinge_period(&scene, w);
        let case = format!("near-degenerate triangle, aspect {aspect:.0}");
        fold_case(&case, scene, w, target, t);
    }
}

/// A jump of the rest angle from 0 to the full 90 degrees within one
/// communication step of 1 us (a hinge period is 17.5 ms), then held: the
/// crease snaps, the energy put in by the jump only decreases afterwards,
/// and after 20 hinge periods the fold is within 1e-4 rad of the target.
/// Tolerance 1e-4: at the default 1e-6 the controller resolves the panels'
/// ringing for the first two periods with ~1 us steps (64k steps, 16 s).
/// An ideal actuator (time constant 0), so that the rest angle itself
/// jumps (the default actuator would spread the jump over its response).
#[test]
fn rest_angle_jump_in_one_communication_step() {
    let target = PI / 2.0;
    for &integrator in INTEGRATORS {
        let clock = Instant::now();
        let mut scene = two_panels(W, target, integrator);
        scene.actuator_time_constant = Some(0.0);
        scene.solver.tolerance = 1e-4;
        let t = hinge_period(&scene, W);
        let mut m = Model::new(scene).unwrap();
        m.initialize().unwrap();
        let mut run = Run::default();
        drive(&mut m, &mut run, &[(1e-6, 1.0)], 1e-6);
        let jumped = total_energy(&m);
        drive(&mut m, &mut run, &[(20.0 * t, 1.0)], 1e-3);
        let what = format!(
            "{integrator:?}, jump within a 1 us step, then 1 ms steps to 20 T (T = {t:.3e} s)"
        );
        let note = format!("energy after the jump {jumped:.2e} J; ");
        let case = "rest angle jump 0 -> 90 deg";
        check_end(case, &what, &note, &m, W, target, &run, clock);
    }
}

/// A communication step of 1 s on a scene whose hinge period is 1 ms
/// (4 mm paper panels, crease stiffness chosen for T = 1 ms): the fold input
/// ramps from 0 to 90 degrees over one 1 s step (quasi-static for the
/// scene), and a second 1 s step holds it. Default solver settings (step at
/// most 1 ms). After the first step the angle lags the target by less than
/// 1e-3 rad, after the second it is within 1e-6 rad.
#[test]
fn one_second_step_on_a_1_ms_scene() {
    let target = PI / 2.0;
    let w = 0.004;
    for &integrator in INTEGRATORS {
        let clock = Instant::now();
        let mut scene = two_panels(w, target, integrator);
        let mt = scene.material;
        let omega = 2.0 * PI / 1e-3;
        scene.crease =
            CreaseStiffness::PerLength(omega * omega * mt.density * mt.thickness * w.powi(3) / 3.0);
        let t = hinge_period(&scene, w);
        let mut m = Model::new(scene).unwrap();
        m.initialize().unwrap();
        let mut run = Run::default();
        drive(&mut m, &mut run, &[(1.0, 1.0)], 1.0);
        let lag = (crease_angle(&m) - target).abs();
        drive(&mut m, &mut run, &[(2.0, 1.0)], 1.0);
        let what = format!(
            "{integrator:?}, T = {t:.3e} s; fold 0 -> 90 deg over one 1 s step, hold one 1 s step"
        );
        let note = format!("lag after the ramp {lag:.1e} rad; final ");
        let case = "1 s communication step, 1 ms scene";
        let angle_err = check_end(case, &what, &note, &m, w, target, &run, clock);
        assert!((t - 1e-3).abs() < 1e-9, "hinge period {t}");
        assert!(lag < 1e-3, "lag {lag}");
        assert!(angle_err < 1e-6, "angle error {angle_err}");
    }
}

/// A rigid spin at 100 rad/s of a free, creased 40 mm paper sheet (2 x 2
/// cells, crease along x = 20 mm, no supports, no damping, default solver),
/// about its normal and about the crease line, for one revolution. A rigid
/// rotation strains nothing, but a spinning elastic sheet stretches under
/// its centrifugal load (stress ~ rho omega^2 R^2, R the half diagonal), so
/// strain energy / kinetic energy is bounded by 10 rho omega^2 R^2 / E
/// (= 2e-5) rather than round-off; the crease, which that in-plane load does
/// not bend, stays below 1e-12 of the kinetic energy. Generalized-alpha
/// (rho_inf = 0.8) loses energy over the revolution (the end is below
/// I omega^2 / 2, the loss under 1e-3); on the way the total may exceed it by
/// up to ten times the error tolerance: the physical energy of a dissipative
/// scheme is not monotone, and under error control at tolerance 1e-6 it was
/// measured up to 1.8e-7 above on this mesh and up to 4.3e-6 above on other
/// small meshes, with either shape functions (the former 1e-9 bound held for
/// BCIZ on this mesh only). After one revolution every vertex is back within
/// 1e-3 R.
#[test]
fn rigid_spin_100_rad_per_s() {
    let (a, rate) = (0.04, 100.0);
    for &integrator in INTEGRATORS {
        // Moments of inertia of the square sheet of mass m about its normal
        // and about an in-plane axis through its centre.
        for (axis_name, axis, inertia) in [
            ("normal", Vector3::z(), a * a / 6.0),
            ("crease line", Vector3::y(), a * a / 12.0),
        ] {
            let clock = Instant::now();
            let mesh = origami_fmu::mesh::builders::grid(a, a, 2, 2, &[(1, 0.0)]);
            let mut scene = Scene::with_defaults("spin", mesh);
            scene.auto_damping = false;
            scene.solver.integrator = integrator;
            // A fast spin's phase error grows as tolerance^(2/3): the return
            // asked here needs 1e-5 or finer (at the default 1e-4 it is
            // 3.1e-3 R, docs/validation.md "Stiff and extreme cases").
            scene.solver.tolerance = 1e-6;
            let mt = scene.material;
            let e0 = 0.5 * mt.density * mt.thickness * a * a * inertia * rate * rate;
            let r = a / 2f64.sqrt();
            let centre = Vector3::new(a / 2.0, a / 2.0, 0.0);
            let mut m = Model::new(scene).unwrap();
            m.initialize().unwrap();
            set_velocity(&mut m, |x, _| rigid_rotation(rate * axis, centre, x));
            let n = m.scene().mesh.n_vertices();
            let start: Vec<Vector3<f64>> = (0..n)
                .map(|v| Vector3::from(m.vertex_position(VertexId(v))))
                .collect();
            let mut work = Work::default();
            let (mut strain, mut crease, mut gain, mut loss, mut last) =
                (0.0f64, 0.0f64, f64::NEG_INFINITY, 0.0f64, 0.0f64);
            for _ in 0..100 {
                work.advance(&mut m, 2.0 * PI / rate / 100.0);
                let [ke, se, ce] = m.energies();
                assert!(ke.is_finite() && se.is_finite() && ce.is_finite());
                strain = strain.max(se / ke);
                crease = crease.max(ce / ke);
                let rel = (ke + se + ce) / e0 - 1.0;
                gain = gain.max(rel);
                loss = loss.max(-rel);
                last = rel;
            }
            let back = (0..n)
                .map(|v| (Vector3::from(m.vertex_position(VertexId(v))) - start[v]).norm() / r)
                .fold(0.0, f64::max);
            let bound = 10.0 * mt.density * rate * rate * r * r / mt.youngs_modulus;
            row(
                &format!("rigid spin 100 rad/s about the {axis_name}"),
                &format!("{integrator:?}, free 2 x 2 sheet, one revolution"),
                &work,
                &format!(
                    "max strain/kinetic {strain:.1e} (bound {bound:.0e}), crease/kinetic {crease:.1e}, E/E0 - 1 in [{:.1e}, {gain:.1e}], return error {back:.1e} R",
                    -loss
                ),
                clock,
            );
            assert!(strain < bound, "strain / kinetic {strain} (bound {bound})");
            assert!(crease < 1e-12, "crease / kinetic {crease}");
            let tol = m.scene().solver.tolerance;
            assert!(gain < 10.0 * tol, "energy rose by {gain} (tolerance {tol})");
            assert!(last < 0.0, "energy after one revolution E/E0 - 1 = {last}");
            assert!(loss < 1e-3, "energy lost {loss}");
            assert!(back < 1e-3, "return error {back}");
        }
    }
}
