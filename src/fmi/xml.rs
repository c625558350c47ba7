//! The modelDescription.xml writer: FMI 2.0 co-simulation, generated from
//! the Model's variable tables and the scene's solver block.
//!
//! Value references follow [`super::instance`]: parameters, then inputs,
//! then outputs, contiguous. Output is deterministic (no date), so the
//! checked-in files under `modelDescription/` can be compared byte for byte.

use super::instance::LOG_CATEGORIES;
use super::resources::{MODEL_IDENTIFIER, VERSION};
use crate::model::{Model, VariableSpec};
use std::collections::BTreeSet;
use std::fmt::Write;

/// SI base-unit exponents (kg, m, s, rad) of the unit symbols the model
/// uses; a unit not listed here is declared without a BaseUnit.
fn base_unit(unit: &str) -> Option<[i32; 4]> {
    Some(match unit {
        "m" => [0, 1, 0, 0],
        "rad" => [0, 0, 0, 1],
        "s" => [0, 0, 1, 0],
        "kg" => [1, 0, 0, 0],
        "J" | "N.m" => [1, 2, -2, 0],
        "N" => [1, 1, -2, 0],
        "N/m" => [1, 0, -2, 0],
        "Pa" => [1, -1, -2, 0],
        "kg/m3" => [1, -3, 0, 0],
        "1/s" => [0, 0, -1, 0],
        "m/s" => [0, 1, -1, 0],
        "m/s2" => [0, 1, -2, 0],
        "rad/s" => [0, 0, -1, 1],
        "N/rad" => [1, 1, -2, -1],
        "N.s/rad" => [1, 1, -1, -1],
        "N.m/rad" => [1, 2, -2, -1],
        _ => return None,
    })
}

/// Escape a string for an XML attribute value.
pub fn escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\n' => out.push_str("&#10;"),
            '\t' => out.push_str("&#9;"),
            c if (c as u32) < 0x20 => {}
            c => out.push(c),
        }
    }
    out
}

/// A real number as xs:double, shortest form that reads back exactly.
pub fn real(x: f64) -> String {
    let plain = format!("{x}");
    let exp = format!("{x:e}");
    if plain.len() <= exp.len() { plain } else { exp }
}

/// The complete modelDescription.xml of `model` with `guid`.
pub fn model_description(model: &Model, guid: &str) -> String {
    let scene = model.scene();
    let mut x = String::new();
    let w = &mut x;
    let _ = writeln!(w, r#"<?xml version="1.0" encoding="UTF-8"?>"#);
    let _ = writeln!(
        w,
        r#"<fmiModelDescription fmiVersion="2.0" modelName="{}" guid="{}" description="Origami folding dynamics (iso-ANCF cubic triangular shells with crease springs) of the scene {}" generationTool="origami-fmu {VERSION}" variableNamingConvention="structured" numberOfEventIndicators="0">"#,
        escape(&scene.name),
        escape(guid),
        escape(&scene.name),
    );
    let _ = writeln!(
        w,
        r#"  <CoSimulation modelIdentifier="{MODEL_IDENTIFIER}" needsExecutionTool="false" canHandleVariableCommunicationStepSize="true" canInterpolateInputs="true" maxOutputDerivativeOrder="0" canRunAsynchronuously="false" canBeInstantiatedOnlyOncePerProcess="false" canNotUseMemoryManagementFunctions="true" canGetAndSetFMUstate="true" canSerializeFMUstate="true" providesDirectionalDerivative="false"/>"#
    );
    let vars: Vec<&VariableSpec> = model
        .parameters()
        .iter()
        .chain(model.inputs())
        .chain(model.outputs())
        .collect();
    unit_definitions(w, &vars);
    let _ = writeln!(w, "  <LogCategories>");
    for (name, description) in LOG_CATEGORIES {
        let _ = writeln!(
            w,
            r#"    <Category name="{name}" description="{}"/>"#,
            escape(description)
        );
    }
    let _ = writeln!(w, "  </LogCategories>");
    let s = &scene.solver;
    let _ = writeln!(
        w,
        r#"  <DefaultExperiment startTime="0" stopTime="{}" tolerance="{}" stepSize="{}"/>"#,
        real(s.stop_time),
        real(s.tolerance),
        real(default_step_size(s.max_step, s.stop_time)),
    );
    let (np, ni) = (model.parameters().len(), model.inputs().len());
    model_variables(w, &vars, np, ni);
    model_structure(w, model, &vars, np, ni);
    let _ = writeln!(w, "</fmiModelDescription>");
    x
}

/// `<UnitDefinitions>` of every unit the variables use.
fn unit_definitions(w: &mut String, vars: &[&VariableSpec]) {
    let units: BTreeSet<&str> = vars
        .iter()
        .map(|v| v.unit.as_str())
        .filter(|u| !u.is_empty())
        .collect();
    if units.is_empty() {
        return;
    }
    let _ = writeln!(w, "  <UnitDefinitions>");
    for u in &units {
        match base_unit(u) {
            Some(e) => {
                let mut attrs = String::new();
                for (name, k) in ["kg", "m", "s", "rad"].iter().zip(e) {
                    if k != 0 {
                        let _ = write!(attrs, r#" {name}="{k}""#);
                    }
                }
                let _ = writeln!(
                    w,
                    r#"    <Unit name="{}"><BaseUnit{attrs}/></Unit>"#,
                    escape(u)
                );
            }
            None => {
                let _ = writeln!(w, r#"    <Unit name="{}"/>"#, escape(u));
            }
        }
    }
    let _ = writeln!(w, "  </UnitDefinitions>");
}

/// `<ModelVariables>`: `np` parameters, then `ni` inputs, then outputs.
fn model_variables(w: &mut String, vars: &[&VariableSpec], np: usize, ni: usize) {
    let _ = writeln!(w, "  <ModelVariables>");
    for (vr, v) in vars.iter().enumerate() {
        let index = vr + 1;
        let (causality, variability, initial, start) = if vr < np {
            ("parameter", "fixed", Some("exact"), true)
        } else if vr < np + ni {
            ("input", "continuous", None, true)
        } else {
            ("output", "continuous", Some("calculated"), false)
        };
        let _ = writeln!(w, "    <!-- index {index} -->");
        let _ = write!(
            w,
            r#"    <ScalarVariable name="{}" valueReference="{vr}" description="{}" causality="{causality}" variability="{variability}""#,
            escape(&v.name),
            escape(&v.description),
        );
        if let Some(i) = initial {
            let _ = write!(w, r#" initial="{i}""#);
        }
        let _ = write!(w, "><Real");
        if !v.unit.is_empty() {
            let _ = write!(w, r#" unit="{}""#, escape(&v.unit));
        }
        if start {
            let _ = write!(w, r#" start="{}""#, real(v.start));
        }
        let _ = writeln!(w, "/></ScalarVariable>");
    }
    let _ = writeln!(w, "  </ModelVariables>");
}

/// `<ModelStructure>`: the outputs, their dependencies, the initial unknowns.
fn model_structure(w: &mut String, model: &Model, vars: &[&VariableSpec], np: usize, ni: usize) {
    let _ = writeln!(w, "  <ModelStructure>");
    let outputs = (np + ni + 1)..=vars.len();
    if !outputs.is_empty() {
        // Outputs are the state at the communication point: an input set
        // now acts over the next step only, except that the crease energy
        // is read under the rest angles in force, which the rest-angle
        // actuators set at once where they are ideal (the default;
        // actuator.time_constant > 0 is a servo): declared whatever the
        // time constant.
        let rest_angle: Vec<String> = model
            .scene()
            .actuators
            .iter()
            .enumerate()
            .filter(|(_, a)| a.mode == crate::scene::ActuatorMode::RestAngle)
            .map(|(k, _)| (np + k + 1).to_string())
            .collect();
        let _ = writeln!(w, "    <Outputs>");
        for i in outputs.clone() {
            let deps = if vars[i - 1].name == "energy.crease" {
                rest_angle.join(" ")
            } else {
                String::new()
            };
            let _ = writeln!(w, r#"      <Unknown index="{i}" dependencies="{deps}"/>"#);
        }
        let _ = writeln!(w, "    </Outputs>");
        let _ = writeln!(w, "    <InitialUnknowns>");
        for i in outputs {
            let _ = writeln!(w, r#"      <Unknown index="{i}"/>"#);
        }
        let _ = writeln!(w, "    </InitialUnknowns>");
    }
    let _ = writeln!(w, "  </ModelStructure>");
}

/// DefaultExperiment stepSize: the largest internal step, unless that
/// would mean more than 10 000 communication points, then stop_time / 10 000.
pub fn default_step_size(max_step: f64, stop_time: f64) -> f64 {
    max_step.max(stop_time / 10_000.0)
}
