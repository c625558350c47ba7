//! The element converges on any triangulation (issue #14's measure): on
//! each mesh family (same diagonal, union-jack, random diagonals, perturbed
//! vertices), case A (small moment, half a turn) and case B (tip force,
//! clamped plate) are within 1 % at 32 cells, converge with observed order of at least 1.5
//! between 16 and 64 cells, and union-jack errors are at most 2x the
//! same-diagonal ones. The studies are `origami_fmu::benchmarks::FamilyStudy`,
//! tabulated by `cargo bench --bench element_families` (docs/validation.md's table).

use origami_fmu::benchmarks::{FamilyStudy, MeshFamily};
use origami_fmu::element::Interpolation;

#[test]
fn every_family_converges() {
    for study in FamilyStudy::ALL {
        let mut same = [0.0; 2];
        for family in MeshFamily::ALL {
            let e = |n| study.error(family, Interpolation::Specht, n).unwrap();
            let (e16, e32, e64) = (e(16), e(32), e(64));
            let order = (e16.abs() / e64.abs()).log2() / 2.0;
            eprintln!(
                "{} / {}: {e16:+.2e} {e32:+.2e} {e64:+.2e}, order {order:.2}",
                study.name(),
                family.name()
            );
            assert!(e32.abs() < 0.01, "{study:?} {family:?}: {e32} at 32 cells");
            assert!(order >= 1.5, "{study:?} {family:?}: order {order}");
            match family {
                MeshFamily::SameDiagonal => same = [e32.abs(), e64.abs()],
                MeshFamily::UnionJack => {
                    assert!(
                        e32.abs() <= 2.0 * same[0] && e64.abs() <= 2.0 * same[1],
                        "{study:?}: union-jack {e32} {e64} vs same diagonal {same:?}"
                    );
                }
                _ => {}
            }
        }
    }
}
