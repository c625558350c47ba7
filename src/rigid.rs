//! Rigid-body motion of the sheet in nodal coordinates, and the part of a
//! velocity that is deformation: what the default damping acts on, so that
//! translations and rotations of the whole sheet (free fall, a spin, a
//! gripper's move) are never damped.
//!
//! A rigid velocity field v(x) = t + w x x moves every position slot by
//! t + w x q_i and turns every gradient slot at w x q_i (gradients do not
//! translate). With the constant mass matrix M = M_s (x) I3, the six modes
//! R and their Gram matrix G = R^T M R follow from M q and the slots' share
//! of the total mass alone, so the projection costs one mass product.
//!
//! A sheet held by moving frames (attachments) has no rigid motion of its
//! own: what is not deformation there is the frames' motion. Its damping
//! acts on the velocity relative to the rigid field that fits the held
//! slots' velocities ([`RigidModes::frame_velocity`]): exactly the frame's
//! for one attachment (or several moving together), zero for supports.

use crate::frame::cross_matrix;
use nalgebra::{DMatrix, Matrix3, Matrix6, SymmetricEigen, Vector3, Vector6};

/// Per-slot data the projection needs, fixed by the mesh.
#[derive(Clone, Debug, Default)]
pub struct RigidModes {
    /// For each slot, sum_j m_ij over the position slots j (zero-free only
    /// for slots coupled to positions): (M_s p)_i with p the position mask.
    pos_mass: Vec<f64>,
    /// Whether each slot is a position slot.
    is_position: Vec<bool>,
    /// The rigid modes the supports allow, as combinations of the six
    /// (columns; translations, then rotations about the origin). All six
    /// for a free sheet, none for a clamped one, the rotations about the
    /// pin for a pinned one.
    allowed: Option<DMatrix<f64>>,
    /// Slots held by frames and supports when the sheet has attachments
    /// (empty otherwise): the rigid field they move with is not damped.
    held: Vec<usize>,
}

fn v3(x: &[f64], s: usize) -> Vector3<f64> {
    Vector3::new(x[3 * s], x[3 * s + 1], x[3 * s + 2])
}

impl RigidModes {
    /// Modes for `n_slots` slots with the given position slots;
    /// `mass_mul` multiplies by M (3 scalars a slot).
    pub fn new(
        n_slots: usize,
        position_slots: impl IntoIterator<Item = usize>,
        mass_mul: impl Fn(&[f64], &mut [f64]),
    ) -> RigidModes {
        let mut is_position = vec![false; n_slots];
        for s in position_slots {
            is_position[s] = true;
        }
        let mut x = vec![0.0; 3 * n_slots];
        for (s, &p) in is_position.iter().enumerate() {
            if p {
                x[3 * s] = 1.0;
            }
        }
        let mut y = vec![0.0; 3 * n_slots];
        mass_mul(&x, &mut y);
        RigidModes {
            pos_mass: (0..n_slots).map(|s| y[3 * s]).collect(),
            is_position,
            allowed: None,
            held: Vec::new(),
        }
    }

    /// Keep the supports and held slots declared on `old` (modes of the
    /// same slots rebuilt for another mass matrix or pattern).
    pub fn keep_constraints(&mut self, old: RigidModes) {
        self.allowed = old.allowed;
        self.held = old.held;
    }

    /// Declare the slots held by frames (and supports) of a sheet with
    /// attachments: damping then acts on the velocity relative to their
    /// rigid motion (see the module docs). Empty: no frames.
    pub fn set_held(&mut self, held: Vec<usize>) {
        self.held = held;
    }

    /// The slots declared with [`RigidModes::set_held`].
    pub fn held(&self) -> &[usize] {
        &self.held
    }

    /// The rigid velocity field (translation `t`, angular velocity `w`
    /// about `c`, the mean held position) that fits the velocities `v` of
    /// the held slots at positions `q` in the least-squares sense: exact
    /// where they move rigidly. None without held slots or where the fit
    /// is singular (no position, or gradients of one direction only).
    pub fn frame_velocity(&self, q: &[f64], v: &[f64]) -> Option<[Vector3<f64>; 3]> {
        let (mut c, mut np) = (Vector3::zeros(), 0usize);
        for &s in self.held.iter().filter(|&&s| self.is_position[s]) {
            c += v3(q, s);
            np += 1;
        }
        if np == 0 {
            return None;
        }
        c /= np as f64;
        // Rows: position v_s = t - [(q_s - c) x] w, gradient v_s = -[q_s x] w.
        let (mut a, mut b) = (Matrix6::<f64>::zeros(), Vector6::<f64>::zeros());
        for &s in &self.held {
            let pos = self.is_position[s];
            let arm = if pos { v3(q, s) - c } else { v3(q, s) };
            let mut rows = nalgebra::Matrix3x6::<f64>::zeros();
            if pos {
                rows.fixed_view_mut::<3, 3>(0, 0)
                    .copy_from(&Matrix3::identity());
            }
            rows.fixed_view_mut::<3, 3>(0, 3)
                .copy_from(&-cross_matrix(&arm));
            a += rows.transpose() * rows;
            b += rows.transpose() * v3(v, s);
        }
        let y = a.cholesky()?.solve(&b);
        Some([y.fixed_rows::<3>(0).into(), y.fixed_rows::<3>(3).into(), c])
    }

    /// Declare the supported scalar DOFs (never moving) at positions `q`:
    /// only rigid modes that leave them at rest remain (the null space of
    /// the modes restricted to them; rotations scaled by the sheet size
    /// `length` so that the threshold is unitless).
    pub fn set_supports(&mut self, supported: &[usize], q: &[f64], length: f64) {
        if supported.is_empty() {
            self.allowed = None;
            return;
        }
        let l = length.max(f64::MIN_POSITIVE);
        let mut sts = Matrix6::<f64>::zeros();
        for &i in supported {
            let (s, c) = (i / 3, i % 3);
            let qs = v3(q, s);
            let mut row = Vector6::zeros();
            if self.is_position[s] {
                row[c] = 1.0;
            }
            for k in 0..3 {
                // Component c of e_k x q_s, per unit of the sheet size.
                let e = Vector3::ith(k, 1.0);
                row[3 + k] = e.cross(&qs)[c] / l;
            }
            sts += row * row.transpose();
        }
        let eig = SymmetricEigen::new(sts);
        let scale = eig.eigenvalues.max().max(1.0);
        let cols: Vec<Vector6<f64>> = (0..6)
            .filter(|&k| eig.eigenvalues[k] <= 1e-10 * scale)
            .map(|k| {
                let mut v = eig.eigenvectors.column(k).into_owned();
                for r in 3..6 {
                    v[r] /= l;
                }
                v
            })
            .collect();
        self.allowed = Some(DMatrix::from_fn(6, cols.len(), |r, c| cols[c][r]));
    }

    /// The total mass and the centre of mass at positions `q`: `m = sum
    /// over the position slots of their mass share`, `m c = sum over all
    /// slots of (M_s p)_s q_s` (the shape functions of the positions sum to
    /// one, so `(M_s p)_s` is the integral of `rho h N_s`).
    pub fn mass_center(&self, q: &[f64]) -> (f64, Vector3<f64>) {
        let (mut m, mut c) = (0.0, Vector3::zeros());
        for (s, &pos) in self.is_position.iter().enumerate() {
            if pos {
                m += self.pos_mass[s];
            }
            c += self.pos_mass[s] * v3(q, s);
        }
        (m, if m > 0.0 { c / m } else { c })
    }

    /// Number of rigid modes the supports allow.
    pub fn n_allowed(&self) -> usize {
        self.allowed.as_ref().map(|a| a.ncols()).unwrap_or(6)
    }

    /// The Gram matrix `G = R^T M R` of the six modes at positions `q`
    /// (`mq` = M q), from the total mass, the first moment and
    /// `Q = sum_i (M q)_i q_i^T`.
    fn gram(&self, q: &[f64], mq: &[f64]) -> Matrix6<f64> {
        let mut m = 0.0;
        let mut c = Vector3::zeros();
        let mut qq = Matrix3::zeros();
        for s in 0..self.is_position.len() {
            let (qs, mqs) = (v3(q, s), v3(mq, s));
            if self.is_position[s] {
                m += self.pos_mass[s];
            }
            c += self.pos_mass[s] * qs;
            qq += mqs * qs.transpose();
        }
        let gtr = -cross_matrix(&c);
        let grr = Matrix3::identity() * qq.trace() - qq;
        let mut g = Matrix6::zeros();
        g.fixed_view_mut::<3, 3>(0, 0)
            .copy_from(&(Matrix3::identity() * m));
        g.fixed_view_mut::<3, 3>(0, 3).copy_from(&gtr);
        g.fixed_view_mut::<3, 3>(3, 0).copy_from(&gtr.transpose());
        g.fixed_view_mut::<3, 3>(3, 3).copy_from(&grr);
        g
    }

    /// Column `k` of `M R` (the momentum of unit mode `k`: translations,
    /// then rotations about the origin) at slot `s`.
    fn mode_momentum(&self, k: usize, s: usize, mq: &[f64]) -> Vector3<f64> {
        let e = Vector3::ith(k % 3, 1.0);
        if k < 3 {
            self.pos_mass[s] * e
        } else {
            e.cross(&v3(mq, s))
        }
    }

    /// The rigid part of the velocity `v` at positions `q`, M-orthogonally
    /// projected, returned as its momentum `M P v` (3 scalars a slot) in
    /// `out`; `mv` = M v and `mq` = M q. None when the sheet has no
    /// well-defined rigid modes (degenerate geometry): then nothing is
    /// projected.
    pub fn rigid_momentum(&self, q: &[f64], mv: &[f64], mq: &[f64], out: &mut [f64]) -> Option<()> {
        let n = self.is_position.len();
        // R^T M v (translation, rotation).
        let (mut bt, mut br) = (Vector3::zeros(), Vector3::zeros());
        for s in 0..n {
            let (qs, mvs) = (v3(q, s), v3(mv, s));
            if self.is_position[s] {
                bt += mvs;
            }
            br += qs.cross(&mvs);
        }
        let g = self.gram(q, mq);
        let mut b = Vector6::zeros();
        b.fixed_rows_mut::<3>(0).copy_from(&bt);
        b.fixed_rows_mut::<3>(3).copy_from(&br);
        let y: Vector6<f64> = match &self.allowed {
            None => g.cholesky()?.solve(&b),
            Some(n) if n.ncols() == 0 => Vector6::zeros(),
            Some(n) => {
                // Restricted to the allowed modes: y = N (N^T G N)^-1 N^T b.
                let gs = n.transpose() * DMatrix::from_column_slice(6, 6, g.as_slice()) * n;
                let bs = n.transpose() * DMatrix::from_column_slice(6, 1, b.as_slice());
                let z = gs.cholesky()?.solve(&bs);
                Vector6::from_column_slice((n * z).as_slice())
            }
        };
        let (yt, yr) = (y.fixed_rows::<3>(0), y.fixed_rows::<3>(3));
        for s in 0..n {
            let f = self.pos_mass[s] * yt + yr.cross(&v3(mq, s));
            out[3 * s..3 * s + 3].copy_from_slice(f.as_slice());
        }
        Some(())
    }

    /// The projection as a dense low-rank matrix: `M P = U G^-1 U^T` with
    /// `U = M R N` (all scalars, column-major, one column per allowed mode)
    /// and `G = N^T R^T M R N` (`N` the allowed combinations, the identity
    /// for a free sheet), at positions `q` (`mq` = M q). None when no mode
    /// is allowed or the modes are degenerate (as [`RigidModes::rigid_momentum`]
    /// then projects nothing).
    pub fn momentum_basis(&self, q: &[f64], mq: &[f64]) -> Option<(Vec<f64>, DMatrix<f64>)> {
        let n_slots = self.is_position.len();
        let g = DMatrix::from_column_slice(6, 6, self.gram(q, mq).as_slice());
        let comb = match &self.allowed {
            None => DMatrix::identity(6, 6),
            Some(n) if n.ncols() == 0 => return None,
            Some(n) => n.clone(),
        };
        let r = comb.ncols();
        let gs = comb.transpose() * &g * &comb;
        // Degenerate modes: nothing is projected.
        gs.clone().cholesky()?;
        let mut u = vec![0.0; 3 * n_slots * r];
        for s in 0..n_slots {
            let cols: [Vector3<f64>; 6] = std::array::from_fn(|k| self.mode_momentum(k, s, mq));
            for j in 0..r {
                let f: Vector3<f64> = (0..6).map(|k| cols[k] * comb[(k, j)]).sum();
                u[j * 3 * n_slots + 3 * s..j * 3 * n_slots + 3 * s + 3]
                    .copy_from_slice(f.as_slice());
            }
        }
        Some((u, gs))
    }

    /// The velocity of the rigid field (translation `t`, angular velocity
    /// `w` about `center`) at positions `q`, written into `v`.
    pub fn rigid_velocity(
        &self,
        q: &[f64],
        t: Vector3<f64>,
        w: Vector3<f64>,
        center: Vector3<f64>,
        v: &mut [f64],
    ) {
        for (s, &pos) in self.is_position.iter().enumerate() {
            let qs = v3(q, s);
            let vs = if pos {
                t + w.cross(&(qs - center))
            } else {
                w.cross(&qs)
            };
            v[3 * s..3 * s + 3].copy_from_slice(vs.as_slice());
        }
    }
}
