//! One panel as users mesh it: a square sheet of a few triangles clamped
//! along one edge under a uniform line load along the opposite edge, its
//! tip deflection against the converged one.

use super::{BenchmarkError, ConstantLoad, MeshFamily, assembler, plate_physics};
use crate::dofs::DofLayout;
use crate::element::ElementOptions;
use crate::ids::VertexId;
use crate::solver::statics::{self, StaticSettings};

/// The converged tip deflection `w D / (p a^3)` of the square panel of
/// [`PanelTip`] (nu = 0.3, mean of its two tip corners): the 16-, 32- and
/// 64-cell values of both bending energies, extrapolated at their observed
/// order (1.5-1.6; 0.338805 and 0.338802; docs/validation.md).
pub const PANEL_TIP: f64 = 0.33880;

/// A square panel, side 1, E = 1e7, nu = 0.3, a/h = 100, clamped along
/// x = 0 (every slot of its vertices held), under the consistent nodal forces
/// of a uniform line load `p` along z on the edge x = 1, small enough for
/// linear theory (w ~ 1e-4 of the side). Two triangles are one cell.
#[derive(Clone, Copy, Debug)]
pub struct PanelTip {
    /// Cells per side (two triangles each).
    pub n: usize,
    /// Triangulation.
    pub family: MeshFamily,
    /// The facets' element.
    pub element: ElementOptions,
}

impl PanelTip {
    /// `n x n` same-diagonal cells, the default element.
    pub fn new(n: usize) -> PanelTip {
        PanelTip {
            n,
            family: MeshFamily::SameDiagonal,
            element: ElementOptions::default(),
        }
    }

    /// The tip deflection `w D / (p a^3)`: the mean of the two tip corners'.
    pub fn solve(&self) -> Result<f64, BenchmarkError> {
        let (a, e, nu, h) = (1.0, 1.0e7, 0.3, 0.01);
        let n = self.n;
        if n == 0 || n > 1000 {
            return Err(BenchmarkError::PlateCells(n));
        }
        let d = e * h * h * h / (12.0 * (1.0 - nu * nu));
        let p = 1e-4 * d / (a * a * a);
        let mesh = self.family.grid(a, a, n, n);
        let layout = DofLayout::new(&mesh);
        let at = |x: f64| -> Vec<VertexId> {
            mesh.vertex_ids()
                .filter(|&v| (mesh.coord(v).x - x).abs() < 1e-12)
                .collect()
        };
        let fixed: Vec<usize> = at(0.0)
            .into_iter()
            .flat_map(|v| layout.vertex_slots(v))
            .collect();
        let mut tip = at(a);
        tip.sort_by(|&u, &v| mesh.coord(u).y.total_cmp(&mesh.coord(v).y));
        let asm = assembler(&mesh, plate_physics(e, nu, h), self.element, &fixed)?;
        // Cubic Hermite side: the shares of p L are 1/2 on each position and
        // 1/12 on each end's gradient towards the other end.
        let mut f = vec![0.0; asm.n_dofs()];
        for w in tip.windows(2) {
            let len = (mesh.coord(w[1]) - mesh.coord(w[0])).norm();
            let (face, tri) = mesh
                .triangles()
                .iter()
                .enumerate()
                .find(|(_, t)| t.contains(&w[0]) && t.contains(&w[1]))
                .expect("a boundary side has its facet");
            let corner = |v: VertexId| tri.iter().position(|&c| c == v).expect("corner");
            let (c0, c1) = (corner(w[0]), corner(w[1]));
            let towards = |c: usize, t: usize| 3 * c + if (c + 1) % 3 == t { 1 } else { 2 };
            let local = &layout.local[face];
            for (k, share) in [
                (3 * c0, 0.5),
                (3 * c1, 0.5),
                (towards(c0, c1), 1.0 / 12.0),
                (towards(c1, c0), 1.0 / 12.0),
            ] {
                for (slot, coeff) in local[k].terms() {
                    f[3 * slot + 2] += coeff * share * p * len;
                }
            }
        }
        let settings = StaticSettings {
            load_steps: 1,
            max_iterations: 20,
            tolerance: 1e-8,
            ..StaticSettings::default()
        };
        let mut q = asm.layout.reference_state(&mesh);
        statics::solve(&asm, &mut q, &[], &ConstantLoad(f), settings)?;
        let corners = [tip[0], tip[tip.len() - 1]];
        let w = corners
            .iter()
            .map(|&v| q[3 * asm.position_slot(v) + 2])
            .sum::<f64>()
            / 2.0;
        Ok(w * d / (p * a * a * a))
    }
}
