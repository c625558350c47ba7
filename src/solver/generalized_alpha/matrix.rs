//! The iteration matrix: where it was formed ([`JacobianPoint`]), forming
//! and factoring it, and re-forming the one a saved state held.

use super::{Coefficients, Workspace};
use crate::assembly::{Assembler, Evaluation, MatrixCoeffs, State};
use crate::frame::Motion;
use crate::solver::SparseSolver;
use crate::solver::stepper::{Drive, Dynamics, StepError};

/// Everything the iteration matrix is a function of: the iterate, the
/// drive and the step size. Saved with the model state, so that a restored
/// state re-forms the very matrix the original run held and continues bit
/// for bit while modified Newton keeps the matrix across communication
/// points.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct JacobianPoint {
    /// Step size.
    pub h: f64,
    /// Positions of the iterate.
    pub q: Vec<f64>,
    /// Velocities of the iterate.
    pub v: Vec<f64>,
    /// Rest angles of the crease ends.
    pub theta0: Vec<f64>,
    /// Applied crease moments.
    pub moment: Vec<f64>,
    /// Unwrapped crease angles at the step start.
    pub theta_prev: Vec<f64>,
    /// Positions and velocities at the step start: what terms lag from
    /// (contact's friction), so a restore forms the same matrix.
    #[serde(default)]
    pub q_start: Vec<f64>,
    /// Velocities at the step start.
    #[serde(default)]
    pub v_start: Vec<f64>,
    /// The moving obstacles' motions at the step start, then at its end
    /// ([`crate::frame::Motion::values`] each): where the barrier had them.
    #[serde(default)]
    pub obstacles: Vec<f64>,
}

/// Factor the iteration matrix formed at `q` (its sparse values in
/// `matrix`) with the dense low-rank part the force terms add to it.
pub(super) fn factor(
    asm: &Assembler,
    solver: &mut SparseSolver,
    matrix: &[f64],
    q: &[f64],
    co: MatrixCoeffs,
) -> Result<(), StepError> {
    solver.factor(matrix).map_err(StepError::Linear)?;
    if let Some(lr) = asm.matrix_low_rank(q, co) {
        solver.set_low_rank(lr).map_err(StepError::Linear)?;
    }
    Ok(())
}

/// Record in `ws` that the solver now holds the matrix formed at `next`
/// for the step from `cur` of size `h` under `drive`, the moving obstacles
/// where `asm` has them (the buffers of `jp`, the point taken out of `ws`
/// before factoring, reused).
#[allow(clippy::too_many_arguments)]
pub(super) fn record(
    asm: &Assembler,
    ws: &mut Workspace,
    jp: Option<JacobianPoint>,
    h: f64,
    next: &Dynamics,
    cur: &Dynamics,
    drive: &Drive,
) {
    let mut jp = jp.unwrap_or_default();
    jp.h = h;
    jp.q.clone_from(&next.q);
    jp.v.clone_from(&next.v);
    jp.theta0.clear();
    jp.theta0.extend_from_slice(drive.theta0);
    jp.moment.clear();
    jp.moment.extend_from_slice(drive.moment);
    jp.theta_prev.clear();
    jp.theta_prev.extend_from_slice(drive.theta_prev);
    jp.q_start.clone_from(&cur.q);
    jp.v_start.clone_from(&cur.v);
    jp.obstacles.clear();
    if let Some((start, end)) = asm.obstacles().map(|o| o.placements()) {
        jp.obstacles
            .extend(start.iter().chain(&end).flat_map(|m| m.values()));
    }
    ws.jacobian = Some(jp);
}

/// Make the solver hold the iteration matrix formed at `point` (None: no
/// matrix, the next step forms one). Nothing to do when it already does;
/// otherwise the matrix is assembled at `point` and factored, which gives
/// bit for bit the factorization the saved run held.
pub(super) fn restore(
    asm: &mut Assembler,
    solver: &mut SparseSolver,
    co: Coefficients,
    point: Option<&JacobianPoint>,
    ws: &mut Workspace,
) -> Result<(), StepError> {
    if ws.jacobian.as_ref() == point {
        return Ok(());
    }
    ws.jacobian = None;
    let Some(p) = point else {
        return Ok(());
    };
    ws.matrix.resize(asm.nnz(), 0.0);
    if !p.obstacles.is_empty() {
        // The moving obstacles where the matrix was formed.
        let m: Vec<Motion> = p
            .obstacles
            .chunks_exact(Motion::VALUES)
            .map(Motion::from_values)
            .collect();
        let (start, end) = m.split_at(m.len() / 2);
        asm.place_bodies(start, end);
    }
    if !p.q_start.is_empty() {
        // The lagged data the matrix was formed with (the next step lags
        // again from its own start).
        asm.lag(&p.q_start, &p.v_start);
    }
    let st = State {
        q: &p.q,
        v: &p.v,
        theta0: &p.theta0,
        moment: &p.moment,
        theta_prev: &p.theta_prev,
    };
    let mut scratch = Evaluation::default();
    let coeffs = co.matrix(p.h);
    asm.evaluate(&st, &mut scratch, Some((&mut ws.matrix[..], coeffs)))
        .map_err(StepError::from)?;
    factor(asm, solver, &ws.matrix, &p.q, coeffs)?;
    ws.jacobian = Some(p.clone());
    Ok(())
}
