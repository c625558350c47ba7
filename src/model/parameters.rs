//! The model's parameters. One row per parameter (the `parameters!` table
//! below) gives its name; its unit, range, description and automatic flag
//! are its row of [`crate::scene::limits::LIMITS`], the one table of named
//! values; [`Parameter::value`] says which scenes have it and its start
//! value, [`Parameter::apply`] how a value goes into the scene (a match
//! over every parameter, so none can be silently ignored).

use super::{Error, Model, Phase, VariableSpec, physics};
use crate::assembly::Physics;
use crate::scene::limits::{Limit, LimitError};
use crate::scene::{ActuatorMode, CreaseStiffness, InputTiming, RampShape as RampShapeKind, Scene};

/// Whether `sc` has an actuator that the built-in ramp drives.
fn has_rest_angle_actuator(sc: &Scene) -> bool {
    sc.actuators
        .iter()
        .any(|a| a.mode == ActuatorMode::RestAngle)
}

/// Whether `sc` has any input.
fn has_inputs(sc: &Scene) -> bool {
    !super::variables::input_table(sc).is_empty()
}

/// Declares [`Parameter`] and [`ALL`] from one row per parameter, in the
/// FMU's order: `Variant => name`. Each name's unit, range, description and
/// automatic flag are its row of [`crate::scene::limits::LIMITS`].
macro_rules! parameters {
    ($($(#[doc = $doc:literal])* $p:ident => $name:literal,)*) => {
        /// One parameter of the model.
        #[derive(Clone, Copy, Debug, PartialEq, Eq)]
        pub(super) enum Parameter {
            $($(#[doc = $doc])* $p,)*
        }

        /// Every parameter, in the FMU's order (value references follow it).
        const ALL: &[Parameter] = &[$(Parameter::$p,)*];

        impl Parameter {
            /// The FMU variable name.
            pub(super) fn name(self) -> &'static str {
                match self {
                    $(Parameter::$p => $name,)*
                }
            }
        }
    };
}

parameters! {
    YoungsModulus => "material.youngs_modulus",
    PoissonRatio => "material.poisson_ratio",
    Thickness => "material.thickness",
    Density => "material.density",
    /// Only in scenes whose crease stiffness is a length scale.
    CreaseLengthScale => "crease.length_scale",
    /// Only in scenes whose crease stiffness is given per unit length.
    CreaseStiffnessPerLength => "crease.stiffness_per_length",
    DampingAlpha => "damping.alpha",
    DampingBeta => "damping.beta",
    DampingCrease => "damping.crease",
    /// Gravity components are only in scenes with gravity.
    GravityX => "gravity.x",
    GravityY => "gravity.y",
    GravityZ => "gravity.z",
    RhoInf => "solver.rho_inf",
    MaxStep => "solver.max_step",
    Tolerance => "solver.tolerance",
    MaxInternalSteps => "solver.max_internal_steps",
    MaxStepCpu => "solver.max_step_cpu",
    ErrorFilter => "solver.error_filter",
    /// Only in scenes with inputs.
    InputFirstOrderHold => "input.first_order_hold",
    /// Only in scenes with contact.
    ContactFriction => "contact.friction",
    /// Only in scenes with actuators.
    ActuatorTimeConstant => "actuator.time_constant",
    /// Only in scenes with a rest-angle actuator.
    RampTime => "ramp.time",
    /// Only in scenes with a rest-angle actuator.
    RampShape => "ramp.shape",
}

use Parameter::*;

impl Parameter {
    /// Its row of the one table of named values.
    fn limit(self) -> &'static Limit {
        crate::scene::limits::limit(self.name()).expect("every parameter has a limit (tested)")
    }

    /// Whether the model chooses it until set: setting one switches the
    /// automatic damping off.
    pub(super) fn is_damping(self) -> bool {
        self.limit().automatic
    }

    /// Its value in `sc`, where `ph` is `physics(sc)` (the damping in
    /// effect: the automatic choice, unless the scene sets damping); None
    /// when the scene has no such parameter.
    fn value(self, sc: &Scene, ph: &Physics) -> Option<f64> {
        match self {
            DampingAlpha => Some(ph.alpha),
            DampingBeta => Some(ph.beta),
            DampingCrease => Some(ph.crease_c_per_length),
            ActuatorTimeConstant => {
                (!sc.actuators.is_empty()).then(|| super::actuator_time_constant(sc))
            }
            RampTime | RampShape if !has_rest_angle_actuator(sc) => None,
            InputFirstOrderHold if !has_inputs(sc) => None,
            _ => (self.limit().value)(sc),
        }
    }

    /// Put `x` into the scene. While the scene's automatic damping is on,
    /// the damping parameters only show the values it chose.
    fn apply(self, sc: &mut Scene, x: f64) {
        let auto = sc.auto_damping;
        let gravity = |sc: &mut Scene, c: usize| {
            if let Some(g) = sc.gravity.as_mut() {
                g[c] = x;
            }
        };
        match self {
            YoungsModulus => sc.material.youngs_modulus = x,
            PoissonRatio => sc.material.poisson_ratio = x,
            Thickness => sc.material.thickness = x,
            Density => sc.material.density = x,
            CreaseLengthScale => sc.crease = CreaseStiffness::LengthScale(x),
            CreaseStiffnessPerLength => sc.crease = CreaseStiffness::PerLength(x),
            DampingAlpha if !auto => sc.damping.alpha = x,
            DampingBeta if !auto => sc.damping.beta = x,
            DampingCrease if !auto => sc.damping.crease = x,
            DampingAlpha | DampingBeta | DampingCrease => {}
            GravityX => gravity(sc, 0),
            GravityY => gravity(sc, 1),
            GravityZ => gravity(sc, 2),
            RhoInf => sc.solver.rho_inf = x,
            MaxStep => sc.solver.max_step = x,
            Tolerance => sc.solver.tolerance = x,
            MaxInternalSteps => sc.solver.max_internal_steps = x as usize,
            MaxStepCpu => sc.solver.max_step_cpu = x,
            ErrorFilter => sc.solver.error_filter = x != 0.0,
            InputFirstOrderHold => {
                sc.solver.input_timing = if x == 0.0 {
                    InputTiming::Hold
                } else {
                    InputTiming::FirstOrderHold
                }
            }
            ContactFriction => {
                if let Some(c) = sc.contact.as_mut() {
                    c.friction = x;
                }
            }
            ActuatorTimeConstant => sc.actuator_time_constant = Some(x),
            RampTime => sc.ramp.time = x,
            RampShape => {
                sc.ramp.shape = if x == 0.0 {
                    RampShapeKind::Linear
                } else {
                    RampShapeKind::Smooth
                }
            }
        }
    }

    /// The variable of the FMU.
    fn spec(self, start: f64, sc: &Scene) -> VariableSpec {
        let Limit {
            name,
            unit,
            description,
            ..
        } = *self.limit();
        let auto = if sc.auto_damping && self.is_damping() {
            " (automatic damping until a damping parameter is set)"
        } else {
            ""
        };
        VariableSpec {
            name: name.into(),
            unit: unit.into(),
            description: format!("{description}{auto}"),
            start,
        }
    }
}

/// The parameters of `scene`, in the FMU's order, and their variables.
pub(super) fn parameter_table(scene: &Scene) -> (Vec<Parameter>, Vec<VariableSpec>) {
    let ph = physics(scene);
    ALL.iter()
        .filter_map(|&p| {
            let start = p.value(scene, &ph)?;
            Some((p, p.spec(start, scene)))
        })
        .unzip()
}

impl Model {
    /// Value of parameter `id`.
    pub fn parameter(&self, id: super::ParameterId) -> Result<f64, Error> {
        let i = id.0;
        self.state
            .parameters
            .get(i)
            .copied()
            .ok_or(Error::NoSuchVariable {
                kind: "parameter",
                index: i,
            })
    }

    /// Set parameter `id`; only before [`Model::initialize`]. A non-finite
    /// or out-of-range value is rejected and nothing changes.
    pub fn set_parameter(&mut self, id: super::ParameterId, value: f64) -> Result<(), Error> {
        let i = id.0;
        let spec = self.parameters.get(i).ok_or(Error::NoSuchVariable {
            kind: "parameter",
            index: i,
        })?;
        let kind = self.parameter_kinds[i];
        if self.state.phase != Phase::Setup {
            return Err(Error::Phase(format!(
                "parameter {} can only be set before initialization",
                spec.name
            )));
        }
        let bad = |source| Error::OutOfLimits {
            name: spec.name.clone(),
            value,
            source,
        };
        crate::scene::limits::check(kind.name(), value).map_err(bad)?;
        if kind == MaxStep {
            let mut so = self.scene.solver;
            so.max_step = value;
            crate::scene::limits::check_solver_relations(&so).map_err(bad)?;
        }
        if kind.is_damping() {
            self.state.damping_set = true;
        }
        self.state.parameters[i] = value;
        Ok(())
    }

    /// Put the parameter values into the scene. Automatic damping stays on
    /// until a damping parameter is set; while on, the damping parameters
    /// show the values it chose for the current material.
    pub(super) fn apply_parameters(&mut self) {
        let auto = self.auto_damping && !self.state.damping_set;
        apply(
            &self.parameter_kinds,
            auto,
            &mut self.scene,
            &mut self.state.parameters,
        );
    }

    /// Check parameter values as a saved state holds them (`damping_set`:
    /// whether a damping parameter was set): each by the rules of
    /// [`crate::scene::limits`], as
    /// [`Model::set_parameter`] does, then the scene they make as the scene
    /// reader does. Returns that scene and the values as
    /// [`Model::apply_parameters`] leaves them.
    pub(super) fn check_parameters(
        &self,
        values: &[f64],
        damping_set: bool,
    ) -> Result<(Scene, Vec<f64>), ParametersError> {
        if values.len() != self.parameters.len() {
            return Err(ParametersError::Count {
                given: values.len(),
                parameters: self.parameters.len(),
            });
        }
        for (p, &x) in self.parameter_kinds.iter().zip(values) {
            crate::scene::limits::check(p.name(), x).map_err(|source| ParametersError::Value {
                name: p.name(),
                source,
            })?;
        }
        let mut scene = self.scene.clone();
        let mut values = values.to_vec();
        let auto = self.auto_damping && !damping_set;
        apply(&self.parameter_kinds, auto, &mut scene, &mut values);
        crate::scene::limits::check_scene(&scene).map_err(ParametersError::Scene)?;
        Ok((scene, values))
    }
}

/// Why a saved state's parameter values were refused.
#[derive(Clone, Debug, PartialEq)]
pub enum ParametersError {
    /// Not one value per parameter.
    Count {
        /// Values given.
        given: usize,
        /// The model's parameters.
        parameters: usize,
    },
    /// A value out of its limits.
    Value {
        /// The parameter.
        name: &'static str,
        /// Why.
        source: LimitError,
    },
    /// The values together make a scene out of limits.
    Scene(LimitError),
}

impl std::fmt::Display for ParametersError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ParametersError::Count { given, parameters } => {
                write!(f, "parameters: {given} values; this model has {parameters}")
            }
            ParametersError::Value { name, source } => write!(f, "{name} = {source}"),
            ParametersError::Scene(e) => write!(f, "{e}"),
        }
    }
}

impl std::error::Error for ParametersError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            ParametersError::Count { .. } => None,
            ParametersError::Value { source, .. } | ParametersError::Scene(source) => Some(source),
        }
    }
}

/// Put the values of `kinds` into `sc`. With automatic damping on
/// (`auto_damping`) the damping values show the automatic choices for the
/// material now in the scene.
fn apply(kinds: &[Parameter], auto_damping: bool, sc: &mut Scene, values: &mut [f64]) {
    sc.auto_damping = auto_damping;
    for (p, &x) in kinds.iter().zip(values.iter()) {
        p.apply(sc, x);
    }
    let ph = physics(sc);
    for (p, x) in kinds.iter().zip(values.iter_mut()) {
        if auto_damping
            && p.is_damping()
            && let Some(v) = p.value(sc, &ph)
        {
            *x = v;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_parameter_has_a_limit_and_its_own_name() {
        for (k, p) in ALL.iter().enumerate() {
            assert!(
                crate::scene::limits::limit(p.name()).is_some(),
                "{} has no limit",
                p.name()
            );
            assert!(ALL[..k].iter().all(|q| q.name() != p.name()));
        }
    }

    /// Applying a value to any parameter a scene has changes the value it
    /// reads back: no parameter is ignored.
    #[test]
    fn every_parameter_is_applied() {
        let mesh = crate::mesh::builders::square_with_diagonal(0.1, true, 1.0);
        let mut with_gravity = Scene::with_defaults("sq", mesh);
        with_gravity.gravity = Some([0.0, 0.0, -9.81]);
        with_gravity.auto_damping = false;
        with_gravity.contact = Some(Default::default());
        let mut per_length = with_gravity.clone();
        per_length.crease = CreaseStiffness::PerLength(1e-3);
        let mut seen = Vec::new();
        for scene in [with_gravity, per_length] {
            let (kinds, specs) = parameter_table(&scene);
            for (&p, spec) in kinds.iter().zip(&specs) {
                assert_eq!(p.name(), spec.name);
                let mut sc = scene.clone();
                let x = 2.0 * spec.start + 1.0;
                p.apply(&mut sc, x);
                assert_eq!(p.value(&sc, &physics(&sc)), Some(x), "{}", spec.name);
                seen.push(p);
            }
        }
        assert!(ALL.iter().all(|p| seen.contains(p)));
    }
}
