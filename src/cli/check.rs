//! `origami-fmu check SCENE.fold`: load and validate a scene and print a
//! summary (mesh, DOFs, inputs, outputs, warnings).

use super::CliError;
use crate::mesh::EdgeKind;
use crate::model::Model;
use crate::scene::{self, CreaseStiffness, Integrator, Loaded};
use clap::Args;
use std::path::PathBuf;

/// Validate a FOLD scene and print a summary of its mesh, variables and warnings.
#[derive(Args, Debug)]
pub struct CheckArgs {
    /// The scene: a FOLD file (or a scene JSON).
    scene: PathBuf,
    #[command(flatten)]
    read: super::SceneOptions,
}

/// Run the check; an invalid scene is an error naming the key and reason.
pub fn run(args: CheckArgs) -> Result<(), CliError> {
    let path = args.scene.display().to_string();
    let loaded = if args.scene.extension().is_some_and(|e| e == "json") {
        super::load_scene(&args.scene, &args.read)?
    } else {
        // The warnings go into the summary, not to stderr.
        let mut loaded = super::read_fold(&args.scene, &args.read)?;
        args.read.apply(&mut loaded.scene)?;
        loaded
    };
    super::out(&report(&path, &loaded)?);
    Ok(())
}

/// A number for people: plain when moderate, scientific otherwise.
fn num(x: f64) -> String {
    if x == 0.0 || (1e-3..1e4).contains(&x.abs()) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

fn list(names: &[String]) -> String {
    const SHOWN: usize = 8;
    let mut s = names
        .iter()
        .take(SHOWN)
        .cloned()
        .collect::<Vec<_>>()
        .join(", ");
    if names.len() > SHOWN {
        s.push_str(&format!(", ... ({} more)", names.len() - SHOWN));
    }
    s
}

/// The text `check` prints for a loaded scene: [`summary`] with the
/// loader's notes (unit or scale, F edges, traced faces, split vertices).
pub fn report(path: &str, loaded: &Loaded) -> Result<String, CliError> {
    summary_with(path, &loaded.scene, &loaded.warnings, &loaded.notes)
}

/// The text `check` prints for a valid scene.
pub fn summary(path: &str, scene: &scene::Scene, warnings: &[String]) -> Result<String, CliError> {
    summary_with(path, scene, warnings, &[])
}

/// The material, crease, damping, supports, solver and contact lines.
fn physics_lines(o: &mut String, scene: &scene::Scene) {
    use std::fmt::Write as _;
    let mat = &scene.material;
    let _ = writeln!(
        o,
        "  material:  E = {} Pa, nu = {}, thickness = {} m, density = {} kg/m^3",
        num(mat.youngs_modulus),
        num(mat.poisson_ratio),
        num(mat.thickness),
        num(mat.density)
    );
    let _ = match scene.crease {
        CreaseStiffness::LengthScale(l) => {
            writeln!(
                o,
                "  creases:   stiffness = (length / {} m) x bending stiffness",
                num(l)
            )
        }
        CreaseStiffness::PerLength(k) => {
            writeln!(
                o,
                "  creases:   stiffness = {} N m/(rad m) x length",
                num(k)
            )
        }
    };
    let d = &scene.damping;
    if scene.auto_damping {
        let _ = writeln!(
            o,
            "  damping:   automatic (from the scene's frequencies); crease {} N m s/(rad m)",
            num(d.crease)
        );
    } else {
        let _ = writeln!(
            o,
            "  damping:   alpha = {} 1/s, beta = {} s, crease {} N m s/(rad m)",
            num(d.alpha),
            num(d.beta),
            num(d.crease)
        );
    }
    let fixed: usize = scene.supports.iter().map(|s| s.vertices.len()).sum();
    let _ = writeln!(
        o,
        "  supports:  {} ({fixed} vertices); gravity: {}",
        scene.supports.len(),
        scene
            .gravity
            .map_or("none".to_string(), |g| format!("{g:?} m/s^2"))
    );
    let s = &scene.solver;
    let _ = writeln!(
        o,
        "  solver:    {}, max step {} s, tolerance {}, stop time {} s",
        match s.integrator {
            Integrator::GeneralizedAlpha => format!("generalized-alpha (rho_inf {})", s.rho_inf),
            Integrator::CentralDifference => "central-difference".to_string(),
        },
        num(s.max_step),
        num(s.tolerance),
        num(s.stop_time)
    );
    let _ = match &scene.contact {
        Some(c) => writeln!(
            o,
            "  contact:   on, thickness {} m, barrier width {} of it, friction {}, {} subdivisions \
             per facet side",
            num(c.thickness),
            num(c.width),
            num(c.friction),
            c.subdivisions
        ),
        None => writeln!(o, "  contact:   off (--contact turns it on)"),
    };
}

/// The inputs, the output groups and the parameter count.
fn variable_lines(o: &mut String, scene: &scene::Scene, model: &Model) {
    use std::fmt::Write as _;
    let inputs: Vec<String> = model.inputs().iter().map(|v| v.name.clone()).collect();
    let _ = writeln!(o, "  inputs ({}): {}", inputs.len(), list(&inputs));
    let outs = model.outputs();
    let group = |p: &str| outs.iter().filter(|v| v.name.starts_with(p)).count();
    let _ = writeln!(
        o,
        "  outputs ({}): {} positions, {} fold angles, {} energies{}",
        outs.len(),
        group("vertex["),
        group("crease["),
        group("energy."),
        if scene.contact.is_some() {
            let names: Vec<String> = outs
                .iter()
                .filter(|v| v.name.starts_with("contact.") || v.name == "energy.contact")
                .map(|v| v.name.clone())
                .collect();
            format!("; contact: {}", names.join(", "))
        } else {
            String::new()
        }
    );
    if let Some(sq) = &scene.sequence {
        let stages: Vec<String> = sq
            .stages
            .iter()
            .enumerate()
            .map(|(k, st)| {
                format!(
                    "{} ({} creases, {:.3} of the drive)",
                    sq.stage_name(k),
                    st.targets.len(),
                    st.share
                )
            })
            .collect();
        let _ = writeln!(
            o,
            "  sequence:  {} stages walked by the input '{}' (outputs sequence.stage, \
             sequence.progress): {}",
            stages.len(),
            sq.actuator,
            list(&stages)
        );
    }
    if !scene.obstacles.is_empty() {
        let names: Vec<String> = scene
            .obstacles
            .iter()
            .map(|ob| {
                let moving = if ob.moving {
                    format!(" (moving: pose inputs {0}.x/y/z, {0}.rx/ry/rz)", ob.name)
                } else {
                    String::new()
                };
                format!("{}.force/moment{moving}", ob.name)
            })
            .collect();
        let _ = writeln!(
            o,
            "  obstacles ({}): wrench outputs {}",
            names.len(),
            list(&names)
        );
    }
    let _ = writeln!(o, "  parameters ({})", model.parameters().len());
}

fn summary_with(
    path: &str,
    scene: &scene::Scene,
    warnings: &[String],
    notes: &[String],
) -> Result<String, CliError> {
    use std::fmt::Write as _;
    let m = &scene.mesh;
    let count = |k: EdgeKind| m.edges().iter().filter(|e| e.kind == k).count();
    let creases: Vec<f64> = m.creases().map(|e| e.fold_target).collect();
    let mountains = creases.iter().filter(|&&t| t < 0.0).count();
    let valleys = creases.iter().filter(|&&t| t > 0.0).count();
    let mut o = String::new();
    let _ = writeln!(o, "scene '{}' ({path}): valid", scene.name);
    let _ = writeln!(
        o,
        "  FOLD:      {} vertices, {} edges",
        scene.fold_vertex_count, scene.fold_edge_count
    );
    for n in notes {
        // "label: text" aligned with the lines around it.
        let _ = match n.split_once(": ") {
            Some((label, text)) if label.len() < 10 => {
                writeln!(o, "  {:<11}{text}", format!("{label}:"))
            }
            _ => writeln!(o, "  {n}"),
        };
    }
    let _ = writeln!(
        o,
        "  mesh:      {} vertices, {} facets (triangles); {} creases ({mountains} mountain, \
         {valleys} valley, {} zero targets), {} smooth and {} boundary edges",
        m.n_vertices(),
        m.triangles().len(),
        creases.len(),
        creases.len() - mountains - valleys,
        count(EdgeKind::Smooth),
        count(EdgeKind::Boundary)
    );
    // One model build serves the DOF count and the variable tables.
    let model = Model::new(scene.clone()).map_err(|source| CliError::ModelOf {
        path: path.into(),
        source,
    })?;
    let _ = writeln!(
        o,
        "  DOFs:      {} ({} vector slots: positions and sector gradients)",
        model.n_dofs(),
        model.n_dofs() / 3
    );
    physics_lines(&mut o, scene);
    variable_lines(&mut o, scene, &model);
    let _ = writeln!(o, "  warnings ({})", warnings.len());
    for w in warnings {
        let _ = writeln!(o, "    - {w}");
    }
    Ok(o)
}
