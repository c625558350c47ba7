//! Free vibration of a cantilever square plate (one edge clamped, three
//! free): the lowest natural frequencies of the linearized sheet at its flat
//! reference, `K x = omega^2 M x` with the shell's tangent and its constant
//! mass matrix, against converged Kirchhoff values.

use super::{BenchmarkError, MeshFamily, assembler, plate_physics, reference_stiffness};
use crate::dofs::DofLayout;
use crate::element::ElementOptions;
use crate::solver::linear::SparseSolver;
use nalgebra::{DMatrix, DVector};

/// Converged frequency parameters `omega a^2 sqrt(rho h / D)` of the five
/// lowest modes of the cantilever square plate, nu = 0.3 (Kirchhoff): the
/// 32- and 64-cell values of both bending energies, Richardson-extrapolated
/// at their observed second order (they agree to 2e-5; docs/validation.md).
/// Leissa's Ritz values (NASA SP-160, 1969: 3.4917, 8.5246, 21.429, 27.331,
/// 31.111) lie 0.2-0.6 % above, as upper bounds from few terms do.
pub const CANTILEVER_PLATE_MODES: [f64; 5] = [3.4711, 8.5064, 21.284, 27.199, 30.955];

/// A cantilever square plate, side 1, E = 1e7, nu = 0.3, a/h = 100, unit
/// density, clamped along x = 0 (every slot of its vertices held).
#[derive(Clone, Copy, Debug)]
pub struct CantileverModes {
    /// Cells per side.
    pub n: usize,
    /// Triangulation.
    pub family: MeshFamily,
    /// The facets' element.
    pub element: ElementOptions,
}

impl CantileverModes {
    /// `n x n` same-diagonal cells, the default element.
    pub fn new(n: usize) -> CantileverModes {
        CantileverModes {
            n,
            family: MeshFamily::SameDiagonal,
            element: ElementOptions::default(),
        }
    }

    /// The lowest `count` frequency parameters `omega a^2 sqrt(rho h / D)`,
    /// ascending.
    pub fn solve(&self, count: usize) -> Result<Vec<f64>, BenchmarkError> {
        let (a, e, nu, slenderness) = (1.0, 1.0e7, 0.3, 100.0);
        let h = a / slenderness;
        let n = self.n;
        if n == 0 || n > 1000 {
            return Err(BenchmarkError::PlateCells(n));
        }
        let mesh = self.family.grid(a, a, n, n);
        let layout = DofLayout::new(&mesh);
        let fixed: Vec<usize> = mesh
            .vertex_ids()
            .filter(|&v| mesh.coord(v).x.abs() < 1e-12)
            .flat_map(|v| layout.vertex_slots(v))
            .collect();
        let asm = assembler(&mesh, plate_physics(e, nu, h), self.element, &fixed)?;
        let k = reference_stiffness(&asm, &mesh)
            .map_err(|_| BenchmarkError::Eigen("stiffness not finite"))?;
        let pencil = Pencil {
            col_ptr: &asm.col_ptr,
            row_idx: &asm.row_idx,
            k: &k,
            m: asm.mass_values(),
        };
        let lambda = pencil.lowest(asm.n_free, count)?;
        let d = e * h * h * h / (12.0 * (1.0 - nu * nu));
        let scale = a * a * (h / d).sqrt(); // rho = 1
        Ok(lambda.iter().map(|l| l.sqrt() * scale).collect())
    }
}

/// A symmetric pencil `(K, M)` on one CSC pattern holding both triangles.
struct Pencil<'a> {
    col_ptr: &'a [usize],
    row_idx: &'a [usize],
    k: &'a [f64],
    m: &'a [f64],
}

impl Pencil<'_> {
    fn mul(&self, vals: &[f64], x: &[f64], y: &mut [f64]) {
        y.fill(0.0);
        for (col, xc) in x.iter().enumerate() {
            for p in self.col_ptr[col]..self.col_ptr[col + 1] {
                y[self.row_idx[p]] += vals[p] * xc;
            }
        }
    }

    /// The `count` lowest eigenvalues of `K x = lambda M x` (K positive
    /// definite) by subspace iteration with Rayleigh-Ritz (Bathe's
    /// algorithm): `2 count + 8` vectors, until the wanted values change by
    /// less than 1e-13 relative.
    fn lowest(&self, n: usize, count: usize) -> Result<Vec<f64>, BenchmarkError> {
        let p = (2 * count + 8).min(n);
        if count == 0 || count > p {
            return Err(BenchmarkError::Eigen("fewer unknowns than modes asked"));
        }
        let mut solver = SparseSolver::new(n, self.col_ptr.to_vec(), self.row_idx.to_vec())
            .map_err(|_| BenchmarkError::Eigen("pattern"))?;
        solver
            .factor(self.k)
            .map_err(|_| BenchmarkError::Eigen("stiffness not positive definite"))?;
        let mut rng = crate::rng::XorShift(0x5eed_f00d);
        let mut x = DMatrix::from_fn(n, p, |_, _| rng.uniform() - 0.5);
        let mut last = vec![f64::INFINITY; count];
        let mut col = vec![0.0; n];
        let mut mx = DMatrix::zeros(n, p);
        for _ in 0..500 {
            // y = K^-1 M x, column by column.
            let mut y = DMatrix::zeros(n, p);
            for j in 0..p {
                self.mul(self.m, x.column(j).as_slice(), &mut col);
                mx.set_column(j, &DVector::from_column_slice(&col));
                solver
                    .solve_in_place(&mut col)
                    .map_err(|_| BenchmarkError::Eigen("solve"))?;
                y.set_column(j, &DVector::from_column_slice(&col));
            }
            // Projected pencil: K y = M x, so y^T K y = y^T M x.
            let kr = y.transpose() * &mx;
            let mut my = DMatrix::zeros(n, p);
            for j in 0..p {
                self.mul(self.m, y.column(j).as_slice(), &mut col);
                my.set_column(j, &DVector::from_column_slice(&col));
            }
            let mr = y.transpose() * my;
            let kr = (&kr + kr.transpose()) * 0.5;
            let mr = (&mr + mr.transpose()) * 0.5;
            let l = mr
                .cholesky()
                .ok_or(BenchmarkError::Eigen("projected mass not definite"))?;
            let l_inv = l
                .l()
                .try_inverse()
                .ok_or(BenchmarkError::Eigen("projected mass singular"))?;
            let a = &l_inv * kr * l_inv.transpose();
            let eig = a.symmetric_eigen();
            let mut order: Vec<usize> = (0..p).collect();
            order.sort_by(|&i, &j| eig.eigenvalues[i].total_cmp(&eig.eigenvalues[j]));
            let phi = l_inv.transpose() * &eig.eigenvectors;
            x = &y * phi.select_columns(&order);
            let now: Vec<f64> = order[..count].iter().map(|&i| eig.eigenvalues[i]).collect();
            let done = now
                .iter()
                .zip(&last)
                .all(|(a, b)| (a - b).abs() <= 1e-13 * a.abs());
            last = now;
            if done {
                return Ok(last);
            }
        }
        Err(BenchmarkError::Eigen("subspace iteration did not converge"))
    }
}
