//! `modelDescription.xml` of an FMI 2.0 FMU: the parts a co-simulation importer uses.
//!
//! Only what dsmcosim needs is read: the header, the `<CoSimulation>` capabilities, the
//! default step and the scalar variables. Defaults are those of the FMI 2.0 standard
//! (causality `local`, variability `continuous`, capability flags `false`).

use roxmltree::{Document, Node};

use super::FmuError;

/// What an FMU says about itself.
#[derive(Debug, Clone, PartialEq)]
pub struct ModelDescription {
    /// `fmiVersion`: always `"2.0"` here (other versions are refused while parsing).
    pub fmi_version: String,
    /// `modelName`.
    pub model_name: String,
    /// `guid`: passed back to `fmi2Instantiate`, which checks it against its own.
    pub guid: String,
    /// `generationTool`, if given.
    pub generation_tool: Option<String>,
    /// The `<CoSimulation>` element; `None` for a model-exchange-only FMU, which
    /// [`super::Fmu::load`] refuses.
    pub co_simulation: Option<CoSimulation>,
    /// `<ModelVariables>`, in file order (FMI's 1-based variable index is position + 1).
    pub variables: Vec<ScalarVariable>,
    /// `<DefaultExperiment stepSize>` [s], if given.
    pub default_experiment_step: Option<f64>,
}

/// The `<CoSimulation>` element's attributes that an importer acts on.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CoSimulation {
    /// `modelIdentifier`: the binary's file stem and the prefix-free symbol names' model.
    pub model_identifier: String,
    /// `canGetAndSetFMUstate` (default false): `fmi2GetFMUstate`/`fmi2SetFMUstate` work.
    pub can_get_and_set_fmu_state: bool,
    /// `canSerializeFMUstate` (default false): states can be turned into bytes and back.
    pub can_serialize_fmu_state: bool,
    /// `canHandleVariableCommunicationStepSize` (default false).
    pub can_handle_variable_communication_step_size: bool,
    /// `canBeInstantiatedOnlyOncePerProcess` (default false).
    pub can_be_instantiated_only_once_per_process: bool,
}

/// One `<ScalarVariable>`.
#[derive(Debug, Clone, PartialEq)]
pub struct ScalarVariable {
    /// `name`.
    pub name: String,
    /// `valueReference`: the handle passed to `fmi2Get*`/`fmi2Set*`.
    pub value_reference: u32,
    /// `causality` (default `local`).
    pub causality: Causality,
    /// `variability` (default `continuous`).
    pub variability: Variability,
    /// The type element's name (`<Real>`, `<Integer>`, …).
    pub kind: VarKind,
    /// The type element's `start`, as a number: Real and Integer as written, Boolean as
    /// 0 or 1, Enumeration as its integer; `None` when absent and for String.
    pub start: Option<f64>,
}

/// `causality` of a variable.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Causality {
    /// `parameter`: set before initialization (or while tunable).
    Parameter,
    /// `calculatedParameter`: computed from parameters.
    CalculatedParameter,
    /// `input`: set by the importer between steps.
    Input,
    /// `output`: read by the importer.
    Output,
    /// `local` (the default): internal.
    Local,
    /// `independent`: the time variable.
    Independent,
}

/// `variability` of a variable.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Variability {
    /// `constant`: never changes.
    Constant,
    /// `fixed`: set only before initialization ends.
    Fixed,
    /// `tunable`: may change at event instants.
    Tunable,
    /// `discrete`: changes only at events.
    Discrete,
    /// `continuous` (the default): may change at any time.
    Continuous,
}

/// The variable's type element.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum VarKind {
    /// `<Real>`: `fmi2Real` (double).
    Real,
    /// `<Integer>`: `fmi2Integer` (int).
    Integer,
    /// `<Boolean>`: `fmi2Boolean` (int, 0 or 1).
    Boolean,
    /// `<String>`.
    String,
    /// `<Enumeration>`: an integer at the ABI.
    Enumeration,
}

impl ModelDescription {
    /// Parses the text of a `modelDescription.xml`. Errors name `modelDescription.xml`
    /// and the element or attribute at fault.
    pub fn parse(xml: &str) -> Result<ModelDescription, FmuError> {
        let doc = Document::parse(xml).map_err(|e| bad("xml", e.to_string()))?;
        let root = doc.root_element();
        if root.tag_name().name() != "fmiModelDescription" {
            return Err(bad(
                "fmiModelDescription",
                format!("the root element is <{}>", root.tag_name().name()),
            ));
        }
        let fmi_version = required(root, "fmiVersion")?.to_string();
        if fmi_version != "2.0" {
            return Err(FmuError::UnsupportedVersion {
                version: fmi_version,
            });
        }
        let co_simulation = match child(root, "CoSimulation") {
            None => None,
            Some(cs) => Some(CoSimulation {
                model_identifier: required(cs, "modelIdentifier")?.to_string(),
                can_get_and_set_fmu_state: flag(cs, "canGetAndSetFMUstate")?,
                can_serialize_fmu_state: flag(cs, "canSerializeFMUstate")?,
                can_handle_variable_communication_step_size: flag(
                    cs,
                    "canHandleVariableCommunicationStepSize",
                )?,
                can_be_instantiated_only_once_per_process: flag(
                    cs,
                    "canBeInstantiatedOnlyOncePerProcess",
                )?,
            }),
        };
        let default_experiment_step = match child(root, "DefaultExperiment") {
            None => None,
            Some(de) => optional_number(de, "stepSize")?,
        };
        let variables = match child(root, "ModelVariables") {
            None => Vec::new(),
            Some(mv) => mv
                .children()
                .filter(|n| n.has_tag_name("ScalarVariable"))
                .enumerate()
                .map(|(i, n)| variable(i, n))
                .collect::<Result<_, _>>()?,
        };
        Ok(ModelDescription {
            fmi_version,
            model_name: required(root, "modelName")?.to_string(),
            guid: required(root, "guid")?.to_string(),
            generation_tool: root.attribute("generationTool").map(str::to_string),
            co_simulation,
            variables,
            default_experiment_step,
        })
    }

    /// The variable called `name`, if any.
    pub fn variable(&self, name: &str) -> Option<&ScalarVariable> {
        self.variables.iter().find(|v| v.name == name)
    }
}

/// Reads the `index`-th (0-based) `<ScalarVariable>`.
fn variable(index: usize, n: Node) -> Result<ScalarVariable, FmuError> {
    let at = |attr: &str| format!("ScalarVariable[{}]@{attr}", index + 1);
    let name = n
        .attribute("name")
        .ok_or_else(|| bad(&at("name"), "missing".into()))?
        .to_string();
    let at = |attr: &str| format!("ScalarVariable '{name}'@{attr}");
    let vr = n
        .attribute("valueReference")
        .ok_or_else(|| bad(&at("valueReference"), "missing".into()))?;
    let value_reference = vr.trim().parse::<u32>().map_err(|_| {
        bad(
            &at("valueReference"),
            format!("'{vr}' is not a 32-bit unsigned integer"),
        )
    })?;
    let causality = match n.attribute("causality").unwrap_or("local") {
        "parameter" => Causality::Parameter,
        "calculatedParameter" => Causality::CalculatedParameter,
        "input" => Causality::Input,
        "output" => Causality::Output,
        "local" => Causality::Local,
        "independent" => Causality::Independent,
        other => return Err(bad(&at("causality"), format!("unknown value '{other}'"))),
    };
    let variability = match n.attribute("variability").unwrap_or("continuous") {
        "constant" => Variability::Constant,
        "fixed" => Variability::Fixed,
        "tunable" => Variability::Tunable,
        "discrete" => Variability::Discrete,
        "continuous" => Variability::Continuous,
        other => return Err(bad(&at("variability"), format!("unknown value '{other}'"))),
    };
    let ty = n.children().find(|c| c.is_element()).ok_or_else(|| {
        bad(
            &at("type"),
            "no <Real>, <Integer>, <Boolean>, <String> or <Enumeration> child".into(),
        )
    })?;
    let kind = match ty.tag_name().name() {
        "Real" => VarKind::Real,
        "Integer" => VarKind::Integer,
        "Boolean" => VarKind::Boolean,
        "String" => VarKind::String,
        "Enumeration" => VarKind::Enumeration,
        other => return Err(bad(&at("type"), format!("unknown type element <{other}>"))),
    };
    let field = format!("ScalarVariable '{name}'/{}@start", ty.tag_name().name());
    let start = match (kind, ty.attribute("start")) {
        (_, None) | (VarKind::String, _) => None,
        (VarKind::Boolean, Some(s)) => Some(match s.trim() {
            "true" | "1" => 1.0,
            "false" | "0" => 0.0,
            _ => return Err(bad(&field, format!("'{s}' is not a boolean"))),
        }),
        (VarKind::Real, Some(s)) => Some(
            s.trim()
                .parse::<f64>()
                .map_err(|_| bad(&field, format!("'{s}' is not a number")))?,
        ),
        (_, Some(s)) => Some(
            s.trim()
                .parse::<i32>()
                .map_err(|_| bad(&field, format!("'{s}' is not a 32-bit integer")))?
                .into(),
        ),
    };
    Ok(ScalarVariable {
        name,
        value_reference,
        causality,
        variability,
        kind,
        start,
    })
}

/// A description error for `field`.
fn bad(field: &str, message: String) -> FmuError {
    FmuError::Description {
        file: "modelDescription.xml".into(),
        field: field.to_string(),
        message,
    }
}

/// The first child element called `name`.
fn child<'a, 'i>(n: Node<'a, 'i>, name: &str) -> Option<Node<'a, 'i>> {
    n.children().find(|c| c.has_tag_name(name))
}

/// Attribute `attr` of `n`, which must be present.
fn required<'a>(n: Node<'a, '_>, attr: &str) -> Result<&'a str, FmuError> {
    n.attribute(attr)
        .ok_or_else(|| bad(&format!("{}@{attr}", n.tag_name().name()), "missing".into()))
}

/// An `xs:boolean` attribute, false when absent.
fn flag(n: Node, attr: &str) -> Result<bool, FmuError> {
    match n.attribute(attr).map(str::trim) {
        None | Some("false") | Some("0") => Ok(false),
        Some("true") | Some("1") => Ok(true),
        Some(other) => Err(bad(
            &format!("{}@{attr}", n.tag_name().name()),
            format!("'{other}' is not a boolean"),
        )),
    }
}

/// An optional number attribute.
fn optional_number(n: Node, attr: &str) -> Result<Option<f64>, FmuError> {
    n.attribute(attr)
        .map(|s| {
            s.trim().parse::<f64>().map_err(|_| {
                bad(
                    &format!("{}@{attr}", n.tag_name().name()),
                    format!("'{s}' is not a number"),
                )
            })
        })
        .transpose()
}

#[cfg(test)]
mod tests {
    use super::*;

    const MINIMAL: &str = r#"<?xml version="1.0"?>
<fmiModelDescription fmiVersion="2.0" modelName="m" guid="{g}">
  <CoSimulation modelIdentifier="m" canGetAndSetFMUstate="true"/>
  <DefaultExperiment stepSize="0.01"/>
  <ModelVariables>
    <ScalarVariable name="k" valueReference="3" causality="parameter" variability="fixed"><Real start="4"/></ScalarVariable>
    <ScalarVariable name="on" valueReference="1"><Boolean start="true"/></ScalarVariable>
    <ScalarVariable name="s" valueReference="2"><String start="x"/></ScalarVariable>
  </ModelVariables>
</fmiModelDescription>"#;

    #[test]
    fn defaults_and_starts_follow_fmi2() {
        let d = ModelDescription::parse(MINIMAL).map_err(|e| e.to_string());
        let d = d.as_ref().map_err(String::as_str);
        assert_eq!(d.map(|d| d.guid.as_str()), Ok("{g}"));
        let Ok(d) = d else { return };
        let cs = d.co_simulation.as_ref();
        assert_eq!(cs.map(|c| c.can_get_and_set_fmu_state), Some(true));
        assert_eq!(cs.map(|c| c.can_serialize_fmu_state), Some(false));
        assert_eq!(d.default_experiment_step, Some(0.01));
        let on = d.variable("on");
        assert_eq!(
            on.map(|v| (v.causality, v.variability)),
            Some((Causality::Local, Variability::Continuous))
        );
        assert_eq!(on.and_then(|v| v.start), Some(1.0));
        assert_eq!(d.variable("k").and_then(|v| v.start), Some(4.0));
        assert_eq!(
            d.variable("s").map(|v| (v.kind, v.start)),
            Some((VarKind::String, None))
        );
    }

    #[test]
    fn a_bad_value_reference_is_named() {
        let xml = MINIMAL.replace("valueReference=\"3\"", "valueReference=\"-3\"");
        let err = ModelDescription::parse(&xml).err().map(|e| e.to_string());
        let err = err.unwrap_or_default();
        assert!(
            err.contains("'k'@valueReference") && err.contains("'-3'"),
            "{err}"
        );
    }
}
