//! Benchmark setups with known answers (BENCHMARKS.md), shared by the
//! integration tests and the cargo benches so both solve the same problem.
//!
//! Case A (Sze, Liu & Lo 2004): a cantilever strip L = 12, b = 1, h = 0.1,
//! E = 1.2e6, nu = 0 (EI = 100), clamped at x = 0 and rolled up by an end
//! moment M; M_max = 2 pi EI / L closes it into a full circle.

use crate::assembly::{Assembler, Physics};
use crate::dofs::DofLayout;
use crate::element::Rule;
use crate::mesh::builders::grid_with;
use crate::scene::Material;
use crate::solver::statics::{self, Load, StaticReport, StaticSettings};
use nalgebra::Matrix3;
use std::f64::consts::PI;

/// Case A strip length.
pub const ROLL_UP_L: f64 = 12.0;
/// Case A bending stiffness E b h^3 / 12.
pub const ROLL_UP_EI: f64 = 100.0;

/// Exact tip displacements `(-u, w)` of case A at `M / M_max = ratio`
/// (the inextensible elastica: the strip bends into a circular arc).
pub fn roll_up_exact(ratio: f64) -> (f64, f64) {
    let t = ratio * 2.0 * PI;
    if t == 0.0 {
        return (0.0, 0.0);
    }
    (
        ROLL_UP_L * (1.0 - t.sin() / t),
        ROLL_UP_L * (1.0 - t.cos()) / t,
    )
}

/// Case A material (E = 1.2e6, nu = 0, h = 0.1, unit density), no creases,
/// no damping.
pub fn roll_up_physics() -> Physics {
    Physics {
        material: Material {
            youngs_modulus: 1.2e6,
            poisson_ratio: 0.0,
            thickness: 0.1,
            density: 1.0,
        },
        crease_k_per_length: 0.0,
        crease_c_per_length: 0.0,
        alpha: 0.0,
        beta: 0.0,
    }
}

/// An end moment about -y, rolling a strip along x towards +z: potential
/// `-M_i psi_i` with `psi_i = atan2(t_z, t_x)` of the x-gradient `t` at each
/// loaded vertex (the projection of the end rotation on the xz-plane).
pub struct EndMoment {
    /// (x-gradient slot, moment at lambda = 1).
    pub slots: Vec<(usize, f64)>,
}

impl Load for EndMoment {
    fn apply(
        &self,
        asm: &Assembler,
        q: &[f64],
        lambda: f64,
        f: &mut [f64],
        matrix: Option<&mut [f64]>,
    ) {
        let mut matrix = matrix;
        for &(s, moment) in &self.slots {
            let m = lambda * moment;
            let (x, z) = (q[3 * s], q[3 * s + 2]);
            let r2 = x * x + z * z;
            f[3 * s] += m * (-z / r2);
            f[3 * s + 2] += m * (x / r2);
            if let Some(vals) = matrix.as_deref_mut() {
                // d2 psi / d(x, z)^2; the potential's Hessian is -m times it.
                let r4 = r2 * r2;
                let mut h = Matrix3::zeros();
                h[(0, 0)] = 2.0 * x * z / r4;
                h[(2, 2)] = -2.0 * x * z / r4;
                h[(0, 2)] = (z * z - x * x) / r4;
                h[(2, 0)] = h[(0, 2)];
                asm.add_block(s, s, &(-m * h), vals);
            }
        }
    }
}

/// One case A run: mesh, restraint and solver settings.
#[derive(Clone, Copy, Debug)]
pub struct RollUp {
    /// Cells along the strip.
    pub nx: usize,
    /// Cells across the strip.
    pub ny: usize,
    /// Alternate the cell diagonals (union-jack mesh) instead of one
    /// direction (three-direction mesh).
    pub alternate: bool,
    /// Hold the width-direction gradient `dr/dY = e_y` at every vertex, so
    /// the strip stays a cylinder about y as the exact solution does (the
    /// free 3D strip turns sideways under this moment, see the tests).
    pub planar: bool,
    /// Static solver settings for the load path up to the largest ratio.
    pub settings: StaticSettings,
}

/// Tip of the strip at one moment level.
#[derive(Clone, Copy, Debug)]
pub struct RollUpPoint {
    /// `M / M_max`.
    pub ratio: f64,
    /// Tip displacement -u (mean of the tip vertices).
    pub u: f64,
    /// Tip displacement w.
    pub w: f64,
    /// Largest sideways displacement |y - Y| of any vertex.
    pub lateral: f64,
    /// Newton iterations from the start of the path to this level.
    pub iterations: usize,
}

/// What a case A run measured.
#[derive(Clone, Debug)]
pub struct RollUpResult {
    /// Free scalar DOFs.
    pub dofs: usize,
    /// One point per requested ratio.
    pub points: Vec<RollUpPoint>,
    /// The static solver's report of the whole path.
    pub report: StaticReport,
}

impl RollUp {
    /// The mesh of the tests and the bench: `nx` x 1 cells, one diagonal
    /// direction, planar; largest increment 1/16 of the path, Newton to a
    /// relative residual of 1e-8.
    pub fn new(nx: usize) -> RollUp {
        RollUp {
            nx,
            ny: 1,
            alternate: false,
            planar: true,
            settings: StaticSettings {
                load_steps: 16,
                max_iterations: 60,
                tolerance: 1e-8,
                min_increment: 1e-6,
            },
        }
    }

    /// Follow one load path up to the largest of `ratios` (increasing, > 0)
    /// and measure the tip at each.
    pub fn solve(&self, ratios: &[f64]) -> Result<RollUpResult, String> {
        let top = ratios.last().copied().unwrap_or(0.0);
        if self.nx == 0 || self.ny == 0 || self.nx > 100_000 || self.ny > 1000 {
            return Err(format!("roll-up: bad mesh {} x {}", self.nx, self.ny));
        }
        if !(top > 0.0 && top.is_finite()) || ratios.windows(2).any(|w| w[1] <= w[0]) {
            return Err("roll-up: ratios must be positive and increasing".into());
        }
        let mesh = grid_with(ROLL_UP_L, 1.0, self.nx, self.ny, &[], self.alternate);
        let physics = roll_up_physics();
        let layout = DofLayout::new(&mesh);
        let nv = mesh.n_vertices();
        let tip: Vec<usize> = (0..nv).filter(|&v| mesh.coords[v].x == ROLL_UP_L).collect();
        // Gradient slot of vertex v along the reference direction `dir`
        // (0 = x, 1 = y): the slot whose sector coefficient is that unit vector.
        let gradient_slot = |v: usize, dir: usize| {
            let sec = &layout.sectors[v];
            let found = sec.first().and_then(|s| {
                s.terms
                    .iter()
                    .find(|(_, c)| (c[dir] - 1.0).abs() < 1e-12 && c[1 - dir].abs() < 1e-12)
            });
            match (sec.len(), found) {
                (1, Some(&(slot, _))) => Ok(slot),
                _ => Err(format!("roll-up: vertex {v} has no plain gradient slot")),
            }
        };
        let mut fixed = Vec::new();
        for v in 0..nv {
            if mesh.coords[v].x == 0.0 {
                fixed.extend(layout.vertex_slots(v));
            } else if self.planar {
                fixed.push(gradient_slot(v, 1)?);
            }
        }
        let asm = Assembler::new(&mesh, physics, Rule::default(), &fixed)?;
        // Trapezoidal shares of the end moment along the tip edge.
        let m_top = top * 2.0 * PI * ROLL_UP_EI / ROLL_UP_L;
        let slots = tip
            .iter()
            .map(|&v| {
                let y = mesh.coords[v].y;
                let share = if y == 0.0 || y == 1.0 { 0.5 } else { 1.0 };
                Ok((gradient_slot(v, 0)?, m_top * share / self.ny as f64))
            })
            .collect::<Result<Vec<_>, String>>()?;
        let load = EndMoment { slots };
        let stops: Vec<f64> = ratios.iter().map(|r| r / top).collect();
        let mut q = asm.layout.reference_state(&mesh);
        let mut points = Vec::new();
        let report = statics::solve_path(
            &asm,
            &mut q,
            &[],
            &load,
            self.settings,
            &stops,
            |lambda, q, report| {
                let pos = |v: usize| {
                    let s = asm.layout.position_slot[v];
                    [q[3 * s], q[3 * s + 1], q[3 * s + 2]]
                };
                let n = tip.len() as f64;
                let x = tip.iter().map(|&v| pos(v)[0]).sum::<f64>() / n;
                let z = tip.iter().map(|&v| pos(v)[2]).sum::<f64>() / n;
                let lateral = (0..nv)
                    .map(|v| (pos(v)[1] - mesh.coords[v].y).abs())
                    .fold(0.0, f64::max);
                points.push(RollUpPoint {
                    ratio: ratios.get(points.len()).copied().unwrap_or(lambda * top),
                    u: ROLL_UP_L - x,
                    w: z,
                    lateral,
                    iterations: report.total_iterations(),
                });
            },
        )?;
        Ok(RollUpResult {
            dofs: asm.n_free,
            points,
            report,
        })
    }
}

/// The Miura-ori scene of `n x n` unit cells with the generator's defaults
/// (20 mm facets, 60 degree sectors): the sheet the throughput and
/// work-precision benches fold.
pub fn miura_scene(n: usize) -> crate::scene::Scene {
    let fold = crate::scene::patterns::Miura {
        nx: n,
        ny: n,
        ..Default::default()
    }
    .generate()
    .expect("valid Miura parameters");
    crate::scene::from_fold(&fold, None)
        .expect("generated Miura scene")
        .0
}

/// Drive a Miura model's `fold` input by the ramp t / `ramp_time` (held
/// at 1 after it) through `steps` communication steps of `dt`, summing
/// the step reports: the fold the throughput, terms and co-simulation
/// benches time. Each step gets the ramp's value at its start and its
/// slope (`with_slopes`, as a master with input derivatives does: the
/// continuous ramp), or only the value (sample and hold).
pub fn fold_by_ramp_with(
    m: &mut crate::model::Model,
    steps: usize,
    dt: f64,
    ramp_time: f64,
    with_slopes: bool,
) -> crate::model::StepReport {
    let fold = m
        .inputs()
        .iter()
        .position(|v| v.name == "fold")
        .expect("a fold input");
    let mut total = crate::model::StepReport::default();
    for k in 0..steps {
        let t = k as f64 * dt;
        m.set_input(fold, (t / ramp_time).min(1.0))
            .expect("fold input in range");
        if with_slopes {
            let slope = if t < ramp_time { 1.0 / ramp_time } else { 0.0 };
            m.set_input_derivative(fold, 1, slope)
                .expect("held inputs take slopes");
        }
        total.accumulate(&m.advance(dt).expect("advance"));
    }
    total
}

/// [`fold_by_ramp_with`] the continuous ramp (values and slopes).
pub fn fold_by_ramp(
    m: &mut crate::model::Model,
    steps: usize,
    dt: f64,
    ramp_time: f64,
) -> crate::model::StepReport {
    fold_by_ramp_with(m, steps, dt, ramp_time, true)
}
