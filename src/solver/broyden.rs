//! Broyden's ("good") secant update of a kept iteration matrix.
//!
//! Modified Newton solves with a matrix `J0` formed at an earlier iterate.
//! Each correction `s_k = H_k g_k` it applies and the residual `g_{k+1}` at
//! its end teach the inverse `H` one direction: `H_{k+1} y_k = s_k` with
//! `y_k = g_k - g_{k+1}` (the residual is the negated force imbalance),
//!
//! `H_{k+1} = H_k + (s_k - H_k y_k) s_k^T W H_k / (s_k^T W H_k y_k)`,
//!
//! in the inner product `W` of the DOFs' scales. Stored as pairs
//! `(s_j, u_j)`, `H_{j+1} x = H_j x + u_j (s_j^T W H_j x)`, applying `H_k`
//! costs one solve with `J0` and `2k` vector operations. Since `H_k g_k =
//! s_k`, the product `H_k y_k = s_k - H_k g_{k+1}` comes from the plain
//! correction at the next iterate: no extra solve. Along a single slow
//! direction the update extrapolates (the new correction is the plain one
//! times `s^T W s / s^T W (s - p)`, Aitken's geometric-series sum).
//!
//! It saves factorizations where a kept matrix contracts slowly along a
//! few directions; it does not remove the second matrix of a folding step
//! (after a rotation the stale matrix is wrong in many directions at once).
//! Whether it earns its place: docs/performance.md, the stepper's rules.

/// The secant history since the matrix was formed.
#[derive(Default)]
pub struct Broyden {
    /// Inner-product weights of the unknowns (`1 / scale^2`).
    weights: Vec<f64>,
    /// Applied corrections `s_j` with an update.
    s: Vec<Vec<f64>>,
    /// Update vectors `u_j`.
    u: Vec<Vec<f64>>,
    /// Pairs in use (the buffers above are kept for reuse).
    len: usize,
    /// The last correction, when it was applied in full (the secant pair's
    /// `s_k`, waiting for the residual at its end).
    last: Option<Vec<f64>>,
    /// Spare buffer for `last`.
    spare: Vec<f64>,
}

/// Updates kept at most; later corrections go on with the matrix and the
/// updates so far (the iteration re-forms the matrix long before).
const MAX_UPDATES: usize = 8;

/// An update whose denominator `s^T W (s - p)` is below this fraction of
/// `s^T W s` (the plain correction repeats the last one: no contraction
/// along it) would extrapolate without bound; it is skipped.
const MIN_DENOMINATOR: f64 = 0.1;

impl Broyden {
    /// Start a new history for `n` unknowns; the caller fills the
    /// returned weights (zero on entry).
    pub fn reset(&mut self, n: usize) -> &mut [f64] {
        self.clear();
        self.weights.clear();
        self.weights.resize(n, 0.0);
        &mut self.weights
    }

    /// Forget the history (a new matrix, or a correction not applied in full).
    pub fn clear(&mut self) {
        self.len = 0;
        if let Some(v) = self.last.take() {
            self.spare = v;
        }
    }

    /// Updates in use.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether no update is in use.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    fn dot(&self, a: &[f64], b: &[f64]) -> f64 {
        self.weights
            .iter()
            .zip(a.iter().zip(b))
            .map(|(w, (x, y))| w * x * y)
            .sum()
    }

    /// Turn `z = J0^-1 g_{k+1}` (the plain correction) into `H_{k+1} g_{k+1}`,
    /// adding the update that the last applied correction and this residual
    /// give.
    pub fn correct(&mut self, z: &mut [f64]) {
        for j in 0..self.len {
            let c = self.dot(&self.s[j], z);
            for (zi, ui) in z.iter_mut().zip(&self.u[j]) {
                *zi += c * ui;
            }
        }
        let Some(s) = self.last.take() else {
            return;
        };
        let ss = self.dot(&s, &s);
        let sp = self.dot(&s, z);
        let den = ss - sp;
        if !(ss > 0.0 && den > MIN_DENOMINATOR * ss) || self.len == MAX_UPDATES {
            self.spare = s;
            return;
        }
        let j = self.len;
        if self.u.len() == j {
            self.u.push(Vec::new());
            self.s.push(Vec::new());
        }
        let u = &mut self.u[j];
        u.clear();
        u.extend(z.iter().map(|p| p / den));
        self.spare = std::mem::replace(&mut self.s[j], s);
        self.len += 1;
        let scale = ss / den;
        for zi in z.iter_mut() {
            *zi *= scale;
        }
    }

    /// Record the correction just computed; `full`: it is applied unscaled
    /// (else no secant pair can be formed from it).
    pub fn applied(&mut self, s: &[f64], full: bool) {
        if !full {
            self.clear();
            return;
        }
        let mut v = self
            .last
            .take()
            .unwrap_or_else(|| std::mem::take(&mut self.spare));
        v.clear();
        v.extend_from_slice(s);
        self.last = Some(v);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Modified Newton on a linear system `A x = b` with a wrong matrix `A0`
    /// converges in at most n + 1 corrections with the updates (Broyden's
    /// method terminates on linear problems), where the plain iteration
    /// contracts at the spectral radius of `I - A0^-1 A`.
    #[test]
    fn secant_updates_converge_where_the_stale_matrix_crawls() {
        // A = diag(1, 2, 3, 4) plus a coupling; A0 = diag(1, 2, 3, 4) * 1.6.
        let n = 4;
        let a = |x: &[f64]| -> Vec<f64> {
            (0..n)
                .map(|i| (i + 1) as f64 * x[i] + 0.3 * x[(i + 1) % n] + 0.3 * x[(i + n - 1) % n])
                .collect()
        };
        let a0_inv =
            |g: &[f64]| -> Vec<f64> { (0..n).map(|i| g[i] / (1.6 * (i + 1) as f64)).collect() };
        let b = [1.0, -2.0, 0.5, 3.0];
        let run = |accelerate: bool| -> usize {
            let mut br = Broyden::default();
            br.reset(n).fill(1.0);
            let mut x = vec![0.0; n];
            for it in 0..200 {
                let ax = a(&x);
                let g: Vec<f64> = (0..n).map(|i| b[i] - ax[i]).collect();
                if g.iter().map(|v| v.abs()).fold(0.0, f64::max) < 1e-12 {
                    return it;
                }
                let mut z = a0_inv(&g);
                if accelerate {
                    br.correct(&mut z);
                    br.applied(&z, true);
                }
                for i in 0..n {
                    x[i] += z[i];
                }
            }
            200
        };
        let plain = run(false);
        let secant = run(true);
        assert!(plain > 30, "plain modified Newton took {plain}");
        assert!(secant <= 2 * n + 2, "with updates {secant}");
    }

    #[test]
    fn a_partial_correction_starts_over() {
        let mut br = Broyden::default();
        br.reset(2).fill(1.0);
        br.applied(&[1.0, 0.0], true);
        let mut z = vec![0.5, 0.0];
        br.correct(&mut z);
        // s = (1,0), p = (0.5,0): extrapolated by 1 / (1 - 0.5).
        assert_eq!(z, vec![1.0, 0.0]);
        assert_eq!(br.len(), 1);
        br.applied(&z, false);
        assert!(br.is_empty());
        let mut z = vec![0.25, 0.0];
        br.correct(&mut z);
        assert_eq!(z, vec![0.25, 0.0]);
    }
}
