//! The force-term interface (issue #10): a term from outside the crate
//! plugs into the assembly with its own force, energy, matrix entries
//! outside the facets' pattern and a per-step hook. The test term is a
//! linear spring between two vertices that share no facet, checked against
//! finite differences through `Assembler::evaluate`.

use nalgebra::{Matrix3, Vector3};
use origami_fmu::assembly::{
    Assembler, BuildError, EvalError, Evaluation, ForceTerm, MatrixCoeffs, Physics, State,
};
use origami_fmu::dofs::DofLayout;
use origami_fmu::element::ElementOptions;
use origami_fmu::ids::VertexId;
use origami_fmu::mesh::builders::grid;
use origami_fmu::scene::Material;
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};

/// A spring `k (|x_a - x_b| - rest)^2 / 2` between the position slots of two vertices.
struct Spring {
    a: usize,
    b: usize,
    k: f64,
    rest: f64,
    hooks: Arc<AtomicUsize>,
}

impl Spring {
    fn ends(&self, asm: &Assembler) -> (usize, usize) {
        (
            asm.position_slot(VertexId(self.a)),
            asm.position_slot(VertexId(self.b)),
        )
    }
}

impl ForceTerm for Spring {
    fn name(&self) -> &str {
        "test spring"
    }

    fn pattern(&self, layout: &DofLayout) -> Vec<(usize, usize)> {
        vec![(layout.position_slot[self.a], layout.position_slot[self.b])]
    }

    fn before_step(&mut self, _asm: &Assembler, _q: &[f64], _v: &[f64]) -> Vec<(usize, usize)> {
        self.hooks.fetch_add(1, Ordering::Relaxed);
        Vec::new()
    }

    fn add(
        &self,
        asm: &Assembler,
        st: &State,
        out: &mut Evaluation,
        matrix: Option<(&mut [f64], MatrixCoeffs)>,
    ) -> Result<(), EvalError> {
        let (sa, sb) = self.ends(asm);
        let x = |s: usize| Vector3::new(st.q[3 * s], st.q[3 * s + 1], st.q[3 * s + 2]);
        let d = x(sa) - x(sb);
        let len = d.norm();
        let u = d / len;
        let stretch = len - self.rest;
        out.term_energy += 0.5 * self.k * stretch * stretch;
        let f = self.k * stretch * u;
        for c in 0..3 {
            out.force[3 * sa + c] += f[c];
            out.force[3 * sb + c] -= f[c];
        }
        if let Some((vals, co)) = matrix {
            let kk = co.k
                * self.k
                * (u * u.transpose() + (stretch / len) * (Matrix3::identity() - u * u.transpose()));
            asm.add_block(sa, sa, &kk, vals);
            asm.add_block(sb, sb, &kk, vals);
            asm.add_block(sa, sb, &(-kk), vals);
            asm.add_block(sb, sa, &(-kk), vals);
        }
        Ok(())
    }
}

fn physics() -> Physics {
    Physics {
        material: Material {
            youngs_modulus: 1e6,
            poisson_ratio: 0.3,
            thickness: 1e-3,
            density: 800.0,
        },
        crease_k_per_length: 0.01,
        crease_c_per_length: 0.0,
        alpha: 0.0,
        beta: 0.0,
    }
}

#[test]
fn an_outside_term_adds_force_energy_matrix_and_hook() {
    let mesh = grid(1.0, 1.0, 3, 3, &[(1, 0.5)]);
    let (a, b) = (0, mesh.n_vertices() - 1); // opposite corners: no common facet
    let hooks = Arc::new(AtomicUsize::new(0));
    let spring = Spring {
        a,
        b,
        k: 3.0,
        rest: 1.0,
        hooks: hooks.clone(),
    };
    let plain = Assembler::new(&mesh, physics(), ElementOptions::default(), &[]).unwrap();
    let mut asm = Assembler::with_terms(
        &mesh,
        physics(),
        ElementOptions::default(),
        &[],
        vec![Box::new(spring)],
    )
    .unwrap();
    assert_eq!(
        asm.term_names(),
        ["shell", "crease springs", "mass damping", "test spring"]
    );
    assert!(
        asm.nnz() > plain.nnz(),
        "the spring's blocks join the pattern"
    );

    // A deformed state: the reference plus a smooth out-of-plane field.
    let mut q = asm.layout.reference_state(&mesh);
    for (i, x) in q.iter_mut().enumerate() {
        *x += 1e-2 * ((i as f64) * 0.37).sin();
    }
    let zeros = vec![0.0; q.len()];
    let theta0 = vec![std::f64::consts::PI; asm.creases.len()];
    let moment = vec![0.0; asm.creases.len()];
    let st = |q: &[f64]| -> (Evaluation, f64) {
        let s = State {
            q,
            v: &zeros,
            theta0: &theta0,
            moment: &moment,
            theta_prev: &theta0,
        };
        let mut ev = Evaluation::default();
        asm.evaluate(&s, &mut ev, None).unwrap();
        let e = ev.term_energy;
        (ev, e)
    };
    let (ev, energy) = st(&q);
    assert!(energy > 0.0);
    // Force of the term = d(term energy)/dq, by central differences.
    let h = 1e-6;
    let (sa, sb) = (
        asm.position_slot(VertexId(a)),
        asm.position_slot(VertexId(b)),
    );
    let mut plain_ev = Evaluation::default();
    let s0 = State {
        q: &q,
        v: &zeros,
        theta0: &theta0,
        moment: &moment,
        theta_prev: &theta0,
    };
    plain.evaluate(&s0, &mut plain_ev, None).unwrap();
    for i in (3 * sa..3 * sa + 3).chain(3 * sb..3 * sb + 3) {
        let mut qp = q.clone();
        let mut qm = q.clone();
        qp[i] += h;
        qm[i] -= h;
        let fd = (st(&qp).1 - st(&qm).1) / (2.0 * h);
        let term_force = ev.force[i] - plain_ev.force[i];
        assert!(
            (fd - term_force).abs() < 1e-7,
            "dof {i}: {fd} vs {term_force}"
        );
    }
    // Its matrix blocks = d(force)/dq: the matrix with the term minus without.
    let co = MatrixCoeffs {
        k: 1.0,
        m: 0.0,
        c: 0.0,
    };
    let mut vals = vec![0.0; asm.nnz()];
    let mut ev2 = Evaluation::default();
    asm.evaluate(&s0, &mut ev2, Some((&mut vals, co))).unwrap();
    let entry = |r: usize, c: usize| -> f64 {
        let (fr, fc) = (asm.free[r], asm.free[c]);
        let range = asm.col_ptr[fc]..asm.col_ptr[fc + 1];
        let k = asm.row_idx[range.clone()].binary_search(&fr).unwrap();
        vals[range.start + k]
    };
    for j in 0..3 {
        let col = 3 * sb + j;
        let mut qp = q.clone();
        let mut qm = q.clone();
        qp[col] += h;
        qm[col] -= h;
        for i in 0..3 {
            let row = 3 * sa + i;
            let fd = (st(&qp).0.force[row] - st(&qm).0.force[row]) / (2.0 * h);
            assert!(
                (fd - entry(row, col)).abs() < 1e-6,
                "({row}, {col}): {fd} vs {}",
                entry(row, col)
            );
        }
    }
    // The hook runs once per call.
    asm.before_step(&q, &zeros);
    asm.before_step(&q, &zeros);
    assert_eq!(hooks.load(Ordering::Relaxed), 2);
}

#[test]
fn a_term_pattern_outside_the_slots_is_an_error() {
    struct Bad;
    impl ForceTerm for Bad {
        fn name(&self) -> &str {
            "bad"
        }
        fn pattern(&self, layout: &DofLayout) -> Vec<(usize, usize)> {
            vec![(0, layout.n_slots())]
        }
        fn add(
            &self,
            _: &Assembler,
            _: &State,
            _: &mut Evaluation,
            _: Option<(&mut [f64], MatrixCoeffs)>,
        ) -> Result<(), EvalError> {
            Ok(())
        }
    }
    let mesh = grid(1.0, 1.0, 1, 1, &[]);
    let err = Assembler::with_terms(
        &mesh,
        physics(),
        ElementOptions::default(),
        &[],
        vec![Box::new(Bad)],
    )
    .err()
    .unwrap();
    assert!(matches!(err, BuildError::Pattern { .. }), "{err}");
    assert!(err.to_string().contains("force term bad"), "{err}");
}
