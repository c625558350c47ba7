//! Benchmark setups with known answers (docs/validation.md), shared by the
//! integration tests and the cargo benches so both solve the same problem.
//!
//! Case A (Sze, Liu & Lo 2004): a cantilever strip L = 12, b = 1, h = 0.1,
//! E = 1.2e6, nu = 0 (EI = 100), clamped at x = 0 and rolled up by an end
//! moment M; M_max = 2 pi EI / L closes it into a full circle.

use crate::assembly::{Assembler, BuildError, EvalError, Evaluation, MatrixCoeffs, Physics, State};
use crate::dofs::DofLayout;
use crate::element::ElementOptions;
use crate::ids::VertexId;
use crate::material::Material;
use crate::mesh::Mesh;
use crate::mesh::builders::{Diagonals, grid_family};
use crate::solver::statics::{self, Load, StaticReport, StaticSettings, StaticsError};
use nalgebra::Matrix3;
use std::f64::consts::PI;

mod modes;
mod panel;
pub use modes::{CANTILEVER_PLATE_MODES, CantileverModes};
pub use panel::{PANEL_TIP, PanelTip};

/// Why a benchmark case could not be solved.
#[derive(Clone, Debug, PartialEq)]
pub enum BenchmarkError {
    /// The roll-up mesh is empty or too large.
    BadMesh {
        /// Cells along the strip.
        nx: usize,
        /// Cells across.
        ny: usize,
    },
    /// The roll-up's moment ratios are not positive and increasing.
    BadRatios,
    /// A roll-up vertex has no plain gradient slot to load or hold.
    NoGradientSlot(VertexId),
    /// The plate's cells per side are odd (no centre vertex) or too many.
    PlateCells(usize),
    /// The assembler could not be built.
    Assembly(BuildError),
    /// The static solve failed.
    Statics(StaticsError),
    /// The eigenvalue problem of a vibration case could not be solved (why).
    Eigen(&'static str),
}

impl std::fmt::Display for BenchmarkError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            BenchmarkError::BadMesh { nx, ny } => write!(f, "roll-up: bad mesh {nx} x {ny}"),
            BenchmarkError::BadRatios => {
                write!(f, "roll-up: ratios must be positive and increasing")
            }
            BenchmarkError::NoGradientSlot(v) => {
                write!(f, "roll-up: vertex {v} has no plain gradient slot")
            }
            BenchmarkError::PlateCells(n) => {
                write!(f, "plate: cells per side must be even, got {n}")
            }
            BenchmarkError::Assembly(m) => write!(f, "{m}"),
            BenchmarkError::Statics(e) => write!(f, "{e}"),
            BenchmarkError::Eigen(why) => write!(f, "vibration modes: {why}"),
        }
    }
}

impl std::error::Error for BenchmarkError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            BenchmarkError::Statics(e) => Some(e),
            BenchmarkError::Assembly(e) => Some(e),
            _ => None,
        }
    }
}

impl From<StaticsError> for BenchmarkError {
    fn from(e: StaticsError) -> Self {
        BenchmarkError::Statics(e)
    }
}

/// The assembler of a benchmark.
fn assembler(
    mesh: &Mesh,
    physics: Physics,
    element: ElementOptions,
    fixed: &[usize],
) -> Result<Assembler, BenchmarkError> {
    Assembler::new(mesh, physics, element, fixed).map_err(BenchmarkError::Assembly)
}

/// Triangulations of a structured grid for element convergence studies: a
/// shell element should converge on all of them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MeshFamily {
    /// Every cell split along the same diagonal (three-direction mesh).
    SameDiagonal,
    /// Alternating diagonals ("union-jack").
    UnionJack,
    /// Each cell's diagonal at random (fixed seed).
    RandomDiagonals,
    /// Random diagonals and every vertex moved by up to 0.2 cells (along
    /// the boundary for boundary vertices).
    Perturbed,
}

impl MeshFamily {
    /// All families, in table order.
    pub const ALL: [MeshFamily; 4] = [
        MeshFamily::SameDiagonal,
        MeshFamily::UnionJack,
        MeshFamily::RandomDiagonals,
        MeshFamily::Perturbed,
    ];

    /// Short name for tables.
    pub fn name(self) -> &'static str {
        match self {
            MeshFamily::SameDiagonal => "same diagonal",
            MeshFamily::UnionJack => "union-jack",
            MeshFamily::RandomDiagonals => "random diagonals",
            MeshFamily::Perturbed => "perturbed",
        }
    }

    /// The `nx` x `ny` cell mesh of `[0, lx] x [0, ly]`, no creases.
    pub fn grid(self, lx: f64, ly: f64, nx: usize, ny: usize) -> Mesh {
        let (diagonals, jitter) = match self {
            MeshFamily::SameDiagonal => (Diagonals::Same, 0.0),
            MeshFamily::UnionJack => (Diagonals::Alternating, 0.0),
            MeshFamily::RandomDiagonals => (Diagonals::Random(7), 0.0),
            MeshFamily::Perturbed => (Diagonals::Random(11), 0.2),
        };
        grid_family(lx, ly, nx, ny, &[], diagonals, jitter)
    }
}

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
    /// How the cells are triangulated.
    pub family: MeshFamily,
    /// Hold the width-direction gradient `dr/dY = e_y` at every vertex, so
    /// the strip stays a cylinder about y as the exact solution does (the
    /// free 3D strip turns sideways under this moment, see the tests).
    pub planar: bool,
    /// Static solver settings for the load path up to the largest ratio.
    pub settings: StaticSettings,
    /// The facets' element.
    pub element: ElementOptions,
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
            family: MeshFamily::SameDiagonal,
            planar: true,
            settings: StaticSettings {
                load_steps: 16,
                max_iterations: 60,
                tolerance: 1e-8,
                min_increment: 1e-6,
            },
            element: ElementOptions::default(),
        }
    }

    /// Follow one load path up to the largest of `ratios` (increasing, > 0)
    /// and measure the tip at each.
    pub fn solve(&self, ratios: &[f64]) -> Result<RollUpResult, BenchmarkError> {
        let top = ratios.last().copied().unwrap_or(0.0);
        if self.nx == 0 || self.ny == 0 || self.nx > 100_000 || self.ny > 1000 {
            return Err(BenchmarkError::BadMesh {
                nx: self.nx,
                ny: self.ny,
            });
        }
        if !(top > 0.0 && top.is_finite()) || ratios.windows(2).any(|w| w[1] <= w[0]) {
            return Err(BenchmarkError::BadRatios);
        }
        let mesh = self.family.grid(ROLL_UP_L, 1.0, self.nx, self.ny);
        let physics = roll_up_physics();
        let layout = DofLayout::new(&mesh);
        let tip: Vec<VertexId> = mesh
            .vertex_ids()
            .filter(|&v| mesh.coord(v).x == ROLL_UP_L)
            .collect();
        // Gradient slot of vertex v along the reference direction `dir`
        // (0 = x, 1 = y): the slot whose sector coefficient is that unit vector.
        let gradient_slot = |v: VertexId, dir: usize| {
            let sec = &layout.sectors[v.index()];
            let found = sec.first().and_then(|s| {
                s.terms
                    .iter()
                    .find(|(_, c)| (c[dir] - 1.0).abs() < 1e-12 && c[1 - dir].abs() < 1e-12)
            });
            match (sec.len(), found) {
                (1, Some(&(slot, _))) => Ok(slot),
                _ => Err(BenchmarkError::NoGradientSlot(v)),
            }
        };
        let mut fixed = Vec::new();
        for v in mesh.vertex_ids() {
            if mesh.coord(v).x == 0.0 {
                fixed.extend(layout.vertex_slots(v));
            } else if self.planar {
                fixed.push(gradient_slot(v, 1)?);
            }
        }
        let asm = assembler(&mesh, physics, self.element, &fixed)?;
        // Trapezoidal shares of the end moment along the tip edge.
        let m_top = top * 2.0 * PI * ROLL_UP_EI / ROLL_UP_L;
        let slots = tip
            .iter()
            .map(|&v| {
                let y = mesh.coord(v).y;
                let share = if y == 0.0 || y == 1.0 { 0.5 } else { 1.0 };
                Ok((gradient_slot(v, 0)?, m_top * share / self.ny as f64))
            })
            .collect::<Result<Vec<_>, BenchmarkError>>()?;
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
                let pos = |v: VertexId| {
                    let s = asm.position_slot(v);
                    [q[3 * s], q[3 * s + 1], q[3 * s + 2]]
                };
                let n = tip.len() as f64;
                let x = tip.iter().map(|&v| pos(v)[0]).sum::<f64>() / n;
                let z = tip.iter().map(|&v| pos(v)[2]).sum::<f64>() / n;
                let lateral = mesh
                    .vertex_ids()
                    .map(|v| (pos(v)[1] - mesh.coord(v).y).abs())
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

/// A constant external force vector (all DOFs), scaled by the load factor.
struct ConstantLoad(Vec<f64>);
impl Load for ConstantLoad {
    fn apply(&self, _: &Assembler, _: &[f64], lambda: f64, f: &mut [f64], _: Option<&mut [f64]>) {
        for (fi, x) in f.iter_mut().zip(&self.0) {
            *fi += lambda * x;
        }
    }
}

/// Linear-elastic physics with no creases, density 1 and no damping.
pub fn plate_physics(e: f64, nu: f64, h: f64) -> Physics {
    Physics {
        material: Material {
            youngs_modulus: e,
            poisson_ratio: nu,
            thickness: h,
            density: 1.0,
        },
        crease_k_per_length: 0.0,
        crease_c_per_length: 0.0,
        alpha: 0.0,
        beta: 0.0,
    }
}

/// The stiffness matrix at the flat reference state `mesh` is built on,
/// unloaded and at rest (free DOFs, in the pattern order of `asm`).
pub fn reference_stiffness(asm: &Assembler, mesh: &Mesh) -> Result<Vec<f64>, EvalError> {
    let q = asm.layout.reference_state(mesh);
    let zeros = vec![0.0; q.len()];
    let st = State {
        q: &q,
        v: &zeros,
        theta0: &[],
        moment: &[],
        theta_prev: &[],
    };
    let mut k = vec![0.0; asm.row_idx.len()];
    let co = MatrixCoeffs {
        k: 1.0,
        m: 0.0,
        c: 0.0,
    };
    asm.evaluate(&st, &mut Evaluation::default(), Some((&mut k, co)))?;
    Ok(k)
}

/// Supported vertices of a static case.
#[derive(Clone, Copy, Debug)]
pub struct Supports<'a> {
    /// The vertices.
    pub vertices: &'a [VertexId],
    /// Clamped (every slot held) or pinned (position only).
    pub clamped: bool,
}

/// Static solve of `mesh` on `supports` under the load `load(asm)`; the mean
/// z displacement of the `probes` and the static solver's report.
pub fn static_deflection(
    mesh: &Mesh,
    physics: Physics,
    element: ElementOptions,
    supports: Supports,
    load: impl Fn(&Assembler) -> Vec<f64>,
    probes: &[VertexId],
    settings: StaticSettings,
) -> Result<(f64, StaticReport), BenchmarkError> {
    let layout = DofLayout::new(mesh);
    let fixed: Vec<usize> = supports
        .vertices
        .iter()
        .flat_map(|&v| {
            if supports.clamped {
                layout.vertex_slots(v)
            } else {
                vec![layout.position_slot[v.index()]]
            }
        })
        .collect();
    let asm = assembler(mesh, physics, element, &fixed)?;
    let mut q = asm.layout.reference_state(mesh);
    let f = load(&asm);
    let report = statics::solve(&asm, &mut q, &[], &ConstantLoad(f), settings)?;
    let z = |v: VertexId| q[3 * asm.position_slot(v) + 2];
    let w = probes.iter().map(|&v| z(v)).sum::<f64>() / probes.len() as f64;
    Ok((w, report))
}

/// Consistent uniform pressure `p` along +z: the mass matrix (rho = 1,
/// scaled by 1/h) applied to a unit translation.
pub fn pressure_load(asm: &Assembler, p: f64, h: f64) -> Vec<f64> {
    let mut t = vec![0.0; asm.n_dofs()];
    for &s in &asm.layout.position_slot {
        t[3 * s + 2] = p / h;
    }
    let mut f = vec![0.0; asm.n_dofs()];
    asm.mass_mul(&t, &mut f);
    f
}

/// Case B: a square plate, side 1, E = 1e7, nu = 0.3, thickness `1 / slenderness`,
/// its boundary clamped or simply supported, under a uniform load or a
/// central point load small enough for linear theory (w ~ 1e-4 of the plate
/// scale `q a^4 / D`); centre deflection against the series solutions
/// (Timoshenko & Woinowsky-Krieger, to five digits: alpha = 0.0040624 /
/// 0.0012653 uniform, beta = 0.011601 / 0.0056120 point load, simply
/// supported / clamped; docs/validation.md prints them to three).
#[derive(Clone, Copy, Debug)]
pub struct PlateCase {
    /// Cells per side (even, so a vertex sits at the centre).
    pub n: usize,
    /// Clamped (true) or simply supported edges.
    pub clamped: bool,
    /// Uniform pressure (true) or central point load.
    pub uniform: bool,
    /// Side over thickness.
    pub slenderness: f64,
    /// Triangulation.
    pub family: MeshFamily,
    /// The facets' element.
    pub element: ElementOptions,
    /// Static solver settings (one load step, relative residual 1e-8).
    pub settings: StaticSettings,
}

impl PlateCase {
    /// A clamped plate under uniform load on `n x n` same-diagonal cells, a/h = 100.
    pub fn new(n: usize) -> PlateCase {
        PlateCase {
            n,
            clamped: true,
            uniform: true,
            slenderness: 100.0,
            family: MeshFamily::SameDiagonal,
            element: ElementOptions::default(),
            settings: StaticSettings {
                load_steps: 1,
                max_iterations: 20,
                tolerance: 1e-8,
                ..StaticSettings::default()
            },
        }
    }

    /// Centre deflection, exact value and the solver's report.
    pub fn solve(&self) -> Result<(f64, f64, StaticReport), BenchmarkError> {
        let (a, e, nu) = (1.0, 1.0e7, 0.3);
        let h = a / self.slenderness;
        let n = self.n;
        if n < 2 || !n.is_multiple_of(2) || n > 1000 {
            return Err(BenchmarkError::PlateCells(n));
        }
        let d = e * h * h * h / (12.0 * (1.0 - nu * nu));
        let mesh = self.family.grid(a, a, n, n);
        let on_edge = |x: f64| x.abs() < 1e-12 || (x - a).abs() < 1e-12;
        let boundary: Vec<VertexId> = mesh
            .vertex_ids()
            .filter(|&v| on_edge(mesh.coord(v).x) || on_edge(mesh.coord(v).y))
            .collect();
        let centre = VertexId((n / 2) * (n + 1) + n / 2);
        let q = 1e-2 * d / a.powi(4);
        let element = self.element;
        let uniform = self.uniform;
        let (w, report) = static_deflection(
            &mesh,
            plate_physics(e, nu, h),
            element,
            Supports {
                vertices: &boundary,
                clamped: self.clamped,
            },
            |asm| {
                if uniform {
                    pressure_load(asm, q, h)
                } else {
                    let mut f = vec![0.0; asm.n_dofs()];
                    f[3 * asm.position_slot(centre) + 2] = q * a * a;
                    f
                }
            },
            &[centre],
            self.settings,
        )?;
        let coeff = match (self.clamped, uniform) {
            (false, true) => 0.0040624,
            (true, true) => 0.0012653,
            (false, false) => 0.011601,
            (true, false) => 0.0056120,
        };
        Ok((w, coeff * q * a.powi(4) / d, report))
    }
}

/// Case B: a cantilever strip L = 1, b = 0.1, h = 0.01, E = 1e7, nu = 0,
/// clamped at x = 0, a small tip force P (w / L = 3e-4) shared by the tip
/// vertices; tip deflection against P L^3 / (3 EI).
#[derive(Clone, Copy, Debug)]
pub struct TipForce {
    /// Cells along the strip.
    pub nx: usize,
    /// Cells across.
    pub ny: usize,
    /// Triangulation.
    pub family: MeshFamily,
    /// The facets' element.
    pub element: ElementOptions,
}

impl TipForce {
    /// `nx` x 1 same-diagonal cells, default shape functions.
    pub fn new(nx: usize) -> TipForce {
        TipForce {
            nx,
            ny: 1,
            family: MeshFamily::SameDiagonal,
            element: ElementOptions::default(),
        }
    }

    /// Tip deflection (mean of the tip vertices) and the exact value.
    pub fn solve(&self) -> Result<(f64, f64), BenchmarkError> {
        let (l, b, h, e) = (1.0, 0.1, 0.01, 1.0e7);
        let ei = e * b * h * h * h / 12.0;
        let mesh = self.family.grid(l, b, self.nx, self.ny);
        let at = |x: f64| -> Vec<VertexId> {
            mesh.vertex_ids()
                .filter(|&v| (mesh.coord(v).x - x).abs() < 1e-12)
                .collect()
        };
        let (root, tips) = (at(0.0), at(l));
        let p = 1e-3 * ei / (l * l);
        let element = self.element;
        let settings = StaticSettings {
            load_steps: 1,
            max_iterations: 20,
            tolerance: 1e-8,
            ..StaticSettings::default()
        };
        let n_tips = tips.len() as f64;
        let (w, _) = static_deflection(
            &mesh,
            plate_physics(e, 0.0, h),
            element,
            Supports {
                vertices: &root,
                clamped: true,
            },
            |asm| {
                let mut f = vec![0.0; asm.n_dofs()];
                for &v in &tips {
                    f[3 * asm.position_slot(v) + 2] = p / n_tips;
                }
                f
            },
            &tips,
            settings,
        )?;
        Ok((w, p * l * l * l / (3.0 * ei)))
    }
}

/// The element convergence studies over [`MeshFamily`] (shared by
/// `tests/element_families.rs` and `benches/element_families.rs`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FamilyStudy {
    /// Case A, M/M_max = 0.002, free strip of n x 2 cells: w.
    SmallMoment,
    /// Case A, half a turn, planar strip of n x 2 cells: the larger tip error.
    HalfTurn,
    /// Case B, tip force on a strip of n x 2 cells.
    TipForce,
    /// Case B, clamped plate under uniform load, n x n cells.
    ClampedPlate,
}

impl FamilyStudy {
    /// All studies, in table order.
    pub const ALL: [FamilyStudy; 4] = [
        FamilyStudy::SmallMoment,
        FamilyStudy::HalfTurn,
        FamilyStudy::TipForce,
        FamilyStudy::ClampedPlate,
    ];

    /// What it measures, for tables.
    pub fn name(self) -> &'static str {
        match self {
            FamilyStudy::SmallMoment => "A: end moment, M/M_max = 0.002 (w), n x 2 cells",
            FamilyStudy::HalfTurn => "A: end moment, M/M_max = 0.5 (larger of -u, w), n x 2 cells",
            FamilyStudy::TipForce => "B: strip, tip force, n x 2 cells",
            FamilyStudy::ClampedPlate => "B: clamped plate, uniform load, n x n cells",
        }
    }

    /// Signed relative error on `n` cells.
    pub fn error(
        self,
        family: MeshFamily,
        element: impl Into<ElementOptions>,
        n: usize,
    ) -> Result<f64, BenchmarkError> {
        let element = element.into();
        let roll_up = |ratio: f64| -> Result<f64, BenchmarkError> {
            let case = RollUp {
                ny: 2,
                family,
                element,
                planar: ratio > 0.01,
                ..RollUp::new(n)
            };
            let p = case.solve(&[ratio])?.points[0];
            let (ue, we) = roll_up_exact(ratio);
            let (eu, ew) = ((p.u - ue) / ue, (p.w - we) / we);
            Ok(if ratio < 0.01 || ew.abs() > eu.abs() {
                ew
            } else {
                eu
            })
        };
        match self {
            FamilyStudy::SmallMoment => roll_up(0.002),
            FamilyStudy::HalfTurn => roll_up(0.5),
            FamilyStudy::TipForce => {
                let case = TipForce {
                    ny: 2,
                    family,
                    element,
                    ..TipForce::new(n)
                };
                let (w, exact) = case.solve()?;
                Ok((w - exact) / exact)
            }
            FamilyStudy::ClampedPlate => {
                let case = PlateCase {
                    family,
                    element,
                    ..PlateCase::new(n)
                };
                let (w, exact, _) = case.solve()?;
                Ok((w - exact) / exact)
            }
        }
    }
}

/// The deployable: a 0.1 m square, 0.5 mm thick, folded flat on its
/// diagonal by the `fold` input, clamped at a corner, with no mass damping,
/// the trapezoidal rule (rho_inf = 1) and a Newton tolerance of 1e-6, so
/// its energy balance closes; no contact yet (the contact tests, bench and
/// output tests add theirs).
pub fn deployable_scene() -> crate::scene::Scene {
    use crate::scene::{Fix, Support};
    let mut scene = crate::scene::Scene::with_defaults(
        "deploy",
        crate::mesh::builders::square_with_diagonal(0.1, true, PI),
    );
    scene.material.thickness = 5e-4;
    scene.auto_damping = false;
    scene.solver.rho_inf = 1.0;
    scene.solver.tolerance = 1e-6;
    scene.supports.push(Support {
        vertices: vec![VertexId(1)],
        fix: Fix::Clamped,
    });
    scene
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
/// continuous ramp), or only the value (sample and hold). After each step
/// `after_step` sees the model and the reports so far (to read outputs, as
/// `simulate_fmu` does, or to trace the state).
pub fn fold_by_ramp_with(
    m: &mut crate::model::Model,
    steps: usize,
    dt: f64,
    ramp_time: f64,
    with_slopes: bool,
    mut after_step: impl FnMut(&crate::model::Model, &crate::model::StepReport),
) -> crate::model::StepReport {
    let fold = m.input_id("fold").expect("a fold input");
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
        after_step(m, &total);
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
    fold_by_ramp_with(m, steps, dt, ramp_time, true, |_, _| {})
}

/// A square grid of `n x n` unit quads (2 n^2 facets) as a FOLD file
/// without a unit: the large unitless scene of the size test and bench.
pub fn unit_grid_fold(n: usize) -> crate::scene::FoldFile {
    let id = |i: usize, j: usize| j * (n + 1) + i;
    crate::scene::FoldFile {
        vertices_coords: (0..=n)
            .flat_map(|j| (0..=n).map(move |i| vec![i as f64, j as f64]))
            .collect(),
        faces_vertices: (0..n)
            .flat_map(|j| {
                (0..n).map(move |i| vec![id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)])
            })
            .collect(),
        ..Default::default()
    }
}

/// Every crease of `scene` with a target driven to +-180 degrees by the
/// sign of its target (a pattern folded flat along its own M/V
/// assignment).
pub fn fold_flat_by_sign(scene: &mut crate::scene::Scene) {
    for e in 0..scene.mesh.edges().len() {
        let edge = &scene.mesh.edges()[e];
        if edge.kind == crate::mesh::EdgeKind::Crease && edge.fold_target != 0.0 {
            let t = std::f64::consts::PI * edge.fold_target.signum();
            scene
                .mesh
                .set_fold_target(crate::ids::EdgeId(e), t)
                .expect("a crease edge of the mesh takes a target of +-pi");
        }
    }
}

/// The target (rad) of mesh edge `e` in the waterbomb base collapsed flat
/// (`scenes/waterbomb.fold`'s own targets are a 3D waterbomb): the
/// diagonals valley, the midline along x mountain, the midline along y
/// unfolded.
pub fn waterbomb_base_target(mesh: &crate::mesh::Mesh, e: usize) -> f64 {
    let [a, b] = mesh.edges()[e].v;
    let d = mesh.coord(b) - mesh.coord(a);
    if d.x.abs() > 1e-9 && d.y.abs() > 1e-9 {
        std::f64::consts::PI
    } else if d.y.abs() <= 1e-9 {
        -std::f64::consts::PI
    } else {
        0.0
    }
}

/// The text after `name` on the bench's command line (the benches' one
/// argument reader).
pub fn arg_text(name: &str) -> Option<String> {
    let args: Vec<String> = std::env::args().collect();
    args.iter()
        .position(|a| a == name)
        .and_then(|i| args.get(i + 1))
        .cloned()
}

/// The whole-number value after `name` on the bench's command line, or
/// `default`.
pub fn arg(name: &str, default: usize) -> usize {
    arg_text(name).map_or(default, |v| v.parse().expect("a number"))
}

/// Best-of-`repeats` CPU time of `f` on this thread in microseconds (the
/// machine is shared: the best run is the least disturbed).
pub fn best_us(repeats: usize, mut f: impl FnMut()) -> f64 {
    let mut best = f64::INFINITY;
    for _ in 0..repeats {
        let t = crate::cpu_time::CpuInstant::now();
        f();
        best = best.min(t.elapsed().as_secs_f64() * 1e6);
    }
    best
}

/// Largest distance between matching points of `p` and `q` after the
/// best-fit proper rigid motion of `p` onto `q` (Kabsch): the error of a
/// computed shape against an exact one, whatever rigid motion it drifted by.
pub fn aligned_max_distance(p: &[nalgebra::Vector3<f64>], q: &[nalgebra::Vector3<f64>]) -> f64 {
    use nalgebra::{Matrix3, Vector3};
    let n = p.len() as f64;
    let pc = p.iter().sum::<Vector3<f64>>() / n;
    let qc = q.iter().sum::<Vector3<f64>>() / n;
    let mut h = Matrix3::zeros();
    for (a, b) in p.iter().zip(q) {
        h += (a - pc) * (b - qc).transpose();
    }
    let svd = h.svd(true, true);
    let (u, vt) = (svd.u.expect("u"), svd.v_t.expect("v_t"));
    let d = (u * vt).determinant().signum();
    let r = vt.transpose() * Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, d)) * u.transpose();
    p.iter()
        .zip(q)
        .map(|(a, b)| (r * (a - pc) + qc - b).norm())
        .fold(0.0, f64::max)
}

/// The standard flat-folding map of a crease pattern whose creases fold
/// to +-180 degrees or stay flat: facet 0 in place, every other facet
/// reflected across the fully folded creases on a path to it (breadth
/// first over the facets; a crease with another target, or a smooth
/// edge, carries the facet over unchanged). Each vertex takes the position
/// the first facet that reaches it gives (all agree where the pattern is
/// flat-foldable).
pub fn flat_folded_positions(mesh: &crate::mesh::Mesh) -> Vec<nalgebra::Vector2<f64>> {
    use crate::mesh::EdgeKind;
    use nalgebra::{Matrix2, Vector2};
    let nf = mesh.triangles().len();
    // Each facet's map x -> a x + b.
    let mut maps: Vec<Option<(Matrix2<f64>, Vector2<f64>)>> = vec![None; nf];
    let mut out: Vec<Option<Vector2<f64>>> = vec![None; mesh.n_vertices()];
    let mut queue = std::collections::VecDeque::new();
    for root in 0..nf {
        if maps[root].is_some() {
            continue;
        }
        maps[root] = Some((Matrix2::identity(), Vector2::zeros()));
        queue.push_back(root);
        while let Some(f) = queue.pop_front() {
            let (a, b) = maps[f].expect("mapped");
            for v in mesh.triangles()[f] {
                out[v.index()].get_or_insert(a * mesh.coord(v) + b);
            }
            for &e in &mesh.face_edges()[f] {
                let edge = mesh.edge(e);
                let flat = edge.kind == EdgeKind::Crease
                    && (edge.fold_target.abs() - std::f64::consts::PI).abs() < 1e-9;
                for &g in mesh.faces_of(e) {
                    let g = g.index();
                    if maps[g].is_some() {
                        continue;
                    }
                    let m = if flat {
                        // Reflection across the line through the edge.
                        let (p, q) = (mesh.coord(edge.v[0]), mesh.coord(edge.v[1]));
                        let d = (q - p).normalize();
                        let r = Matrix2::new(
                            2.0 * d.x * d.x - 1.0,
                            2.0 * d.x * d.y,
                            2.0 * d.x * d.y,
                            2.0 * d.y * d.y - 1.0,
                        );
                        (a * r, a * (p - r * p) + b)
                    } else {
                        (a, b)
                    };
                    maps[g] = Some(m);
                    queue.push_back(g);
                }
            }
        }
    }
    out.into_iter().map(|p| p.unwrap_or_default()).collect()
}

/// How far a folded state `x` (every mesh vertex) is from the flat-folding
/// map `map` ([`flat_folded_positions`]), as a share of the folded size
/// (the longest side of the map's bounding box): seen in the best-fit
/// plane of `x` (out of it the layers keep their thickness apart), the
/// largest in-plane distance after the best-fit rigid motion in the plane
/// (reflections included: the plane has no preferred side).
pub fn flat_fold_error(map: &[nalgebra::Vector2<f64>], x: &[nalgebra::Vector3<f64>]) -> f64 {
    use nalgebra::{Matrix2, Matrix3, Vector2, Vector3};
    let n = x.len() as f64;
    let c = x.iter().sum::<Vector3<f64>>() / n;
    let mut cov = Matrix3::zeros();
    for p in x {
        cov += (p - c) * (p - c).transpose();
    }
    let eig = cov.symmetric_eigen();
    let mut order = [0, 1, 2];
    order.sort_by(|&i, &j| eig.eigenvalues[j].total_cmp(&eig.eigenvalues[i]));
    let (e1, e2) = (
        eig.eigenvectors.column(order[0]).into_owned(),
        eig.eigenvectors.column(order[1]).into_owned(),
    );
    let inplane: Vec<Vector2<f64>> = x
        .iter()
        .map(|p| Vector2::new((p - c).dot(&e1), (p - c).dot(&e2)))
        .collect();
    let mc = map.iter().sum::<Vector2<f64>>() / n;
    let mut h = Matrix2::zeros();
    for (a, b) in map.iter().zip(&inplane) {
        h += (a - mc) * b.transpose();
    }
    let svd = h.svd(true, true);
    let r = svd.v_t.expect("v_t").transpose() * svd.u.expect("u").transpose();
    let worst = map
        .iter()
        .zip(&inplane)
        .map(|(a, b)| (r * (a - mc) - b).norm())
        .fold(0.0, f64::max);
    let (mut lo, mut hi) = (map[0], map[0]);
    for p in map {
        lo = lo.inf(p);
        hi = hi.sup(p);
    }
    worst / (hi - lo).max()
}

#[cfg(test)]
mod tests {
    use nalgebra::{Rotation3, Vector3};

    /// A rotated and shifted copy is at distance 0; one moved point sets
    /// the distance (up to the share of the fit it pulls).
    #[test]
    fn aligned_distance_ignores_rigid_motion() {
        let p: Vec<Vector3<f64>> = (0..12)
            .map(|i| {
                let t = i as f64;
                Vector3::new(t.cos(), (1.3 * t).sin(), 0.1 * t)
            })
            .collect();
        let r = Rotation3::from_euler_angles(0.3, -1.1, 2.0);
        let shift = Vector3::new(0.5, -2.0, 3.0);
        let mut q: Vec<Vector3<f64>> = p.iter().map(|x| r * x + shift).collect();
        assert!(super::aligned_max_distance(&p, &q) < 1e-12);
        q[4] += r * Vector3::new(0.0, 0.0, 1e-3);
        let d = super::aligned_max_distance(&p, &q);
        // At most 1e-3 (the fit minimises the sum of squares, 1e-6 unaligned).
        assert!((0.7e-3..=1e-3).contains(&d), "{d}");
    }

    /// The diagonal folded onto itself: its far corner lands on the
    /// other; a state in another plane, turned and shifted, with its layers
    /// apart out of the plane, has no in-plane error.
    #[test]
    fn the_flat_folding_map_reflects_across_folded_creases() {
        let mesh = crate::mesh::builders::square_with_diagonal(1.0, true, std::f64::consts::PI);
        let map = super::flat_folded_positions(&mesh);
        // Two of the four corners coincide, the other two are fixed.
        let mut close = 0;
        for i in 0..4 {
            for j in i + 1..4 {
                if (map[i] - map[j]).norm() < 1e-12 {
                    close += 1;
                }
            }
        }
        assert_eq!(close, 1, "{map:?}");
        let r = Rotation3::from_euler_angles(0.4, 0.2, -1.0);
        let x: Vec<Vector3<f64>> = map
            .iter()
            .enumerate()
            .map(|(i, p)| r * Vector3::new(p.x, p.y, 1e-3 * i as f64) + Vector3::new(1.0, 2.0, 3.0))
            .collect();
        assert!(super::flat_fold_error(&map, &x) < 1e-3);
        let mut bad = x.clone();
        bad[0] += r * Vector3::new(0.1, 0.0, 0.0);
        assert!(super::flat_fold_error(&map, &bad) > 0.03);
    }
}
