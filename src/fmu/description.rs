//! `modelDescription.xml` of an FMI 2.0 or FMI 3.0 FMU: the parts a co-simulation
//! importer uses.
//!
//! Only what dsmcosim needs is read: the header, the `<CoSimulation>` capabilities, the
//! default step and the variables. Defaults are those of the standard (causality
//! `local`, capability flags `false`; variability `continuous`, except for FMI 3.0
//! variables of a type other than Float32 and Float64, whose default is `discrete`).
//!
//! The two versions differ in form, not in what is read here:
//!
//! | | FMI 2.0 | FMI 3.0 |
//! |---|---|---|
//! | token checked by the binary | `guid` | `instantiationToken` |
//! | state capabilities | `canGetAndSetFMUstate`, `canSerializeFMUstate` | `canGetAndSetFMUState`, `canSerializeFMUState` |
//! | a variable | `<ScalarVariable …><Real start/></ScalarVariable>` | `<Float64 … start/>` |
//!
//! FMI 3.0 types map onto [`VarKind`]: Float64 → `Real`, Int32 → `Integer`, Boolean →
//! `Boolean`, String → `String`, Enumeration → `Enumeration` (an `Int64` at FMI 3.0's
//! ABI; [`super::Instance`] passes it so); every other type (Float32, Int8 … UInt64,
//! Binary, Clock) reads as [`VarKind::Other`] and a variable with `<Dimension>` children
//! as [`VarKind::Array`]. They load; using one (a connection, a start value) is refused
//! where it is named.

use roxmltree::{Document, Node};

use super::FmuError;

/// What an FMU says about itself.
#[derive(Debug, Clone, PartialEq)]
pub struct ModelDescription {
    /// `fmiVersion`: `"2.0"`, or `"3.0"` (or `"3.0.x"`); other versions are refused while
    /// parsing.
    pub fmi_version: String,
    /// `modelName`.
    pub model_name: String,
    /// `guid` (FMI 2.0) or `instantiationToken` (FMI 3.0): passed back to
    /// `fmi2Instantiate` or `fmi3InstantiateCoSimulation`, which check it against their own.
    pub guid: String,
    /// `generationTool`, if given.
    pub generation_tool: Option<String>,
    /// The `<CoSimulation>` element; `None` for a model-exchange-only FMU, which
    /// [`super::Fmu::load`] refuses.
    pub co_simulation: Option<CoSimulation>,
    /// `<ModelVariables>`, in file order (FMI 2.0's 1-based variable index is position + 1).
    pub variables: Vec<ScalarVariable>,
    /// `<DefaultExperiment stepSize>` [s], if given.
    pub default_experiment_step: Option<f64>,
}

/// The `<CoSimulation>` element's attributes that an importer acts on.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CoSimulation {
    /// `modelIdentifier`: the binary's file stem and the prefix-free symbol names' model.
    pub model_identifier: String,
    /// `canGetAndSetFMUstate` (FMI 2.0) or `canGetAndSetFMUState` (FMI 3.0), default
    /// false: states can be saved and restored.
    pub can_get_and_set_fmu_state: bool,
    /// `canSerializeFMUstate` (FMI 2.0) or `canSerializeFMUState` (FMI 3.0), default
    /// false: states can be turned into bytes and back.
    pub can_serialize_fmu_state: bool,
    /// `canHandleVariableCommunicationStepSize` (default false).
    pub can_handle_variable_communication_step_size: bool,
    /// `canBeInstantiatedOnlyOncePerProcess` (default false).
    pub can_be_instantiated_only_once_per_process: bool,
}

/// One variable: an FMI 2.0 `<ScalarVariable>` or an FMI 3.0 type element (`<Float64>`, …).
#[derive(Debug, Clone, PartialEq)]
pub struct ScalarVariable {
    /// `name`.
    pub name: String,
    /// `valueReference`: the handle passed to `fmi2Get*`/`fmi2Set*` or `fmi3Get*`/`fmi3Set*`.
    pub value_reference: u32,
    /// `causality` (default `local`).
    pub causality: Causality,
    /// `variability` (default `continuous`).
    pub variability: Variability,
    /// The type (`<Real>`, `<Integer>`, … in FMI 2.0; `<Float64>`, `<Int32>`, … in FMI 3.0).
    pub kind: VarKind,
    /// `start`, as a number: Real and Integer as written, Boolean as 0 or 1, Enumeration
    /// as its integer; `None` when absent and for String, [`VarKind::Other`] and
    /// [`VarKind::Array`].
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
    /// `structuralParameter` (FMI 3.0): set only in configuration mode, which dsmcosim
    /// does not enter.
    StructuralParameter,
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

/// The variable's type.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum VarKind {
    /// `<Real>` (`fmi2Real`) or `<Float64>` (`fmi3Float64`): a double.
    Real,
    /// `<Integer>` (`fmi2Integer`, an int) or `<Int32>` (`fmi3Int32`).
    Integer,
    /// `<Boolean>`: `fmi2Boolean` (int, 0 or 1) or `fmi3Boolean` (C `bool`).
    Boolean,
    /// `<String>`.
    String,
    /// `<Enumeration>`: an integer at the ABI (`int` in FMI 2.0, `Int64` in FMI 3.0).
    Enumeration,
    /// An FMI 3.0 type this importer does not exchange, by its element name (`Float32`,
    /// `Int8`, `UInt8`, `Int16`, `UInt16`, `UInt32`, `Int64`, `UInt64`, `Binary`,
    /// `Clock`).
    Other(&'static str),
    /// An FMI 3.0 array variable (it has `<Dimension>` children), by its element type's
    /// name (`Float64`): not exchanged.
    Array(&'static str),
}

impl std::fmt::Display for VarKind {
    /// `Real`, `Integer`, …; an unexchanged FMI 3.0 type by its name (`Float32`), an
    /// array as `Float64 array`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            VarKind::Real => f.write_str("Real"),
            VarKind::Integer => f.write_str("Integer"),
            VarKind::Boolean => f.write_str("Boolean"),
            VarKind::String => f.write_str("String"),
            VarKind::Enumeration => f.write_str("Enumeration"),
            VarKind::Other(name) => f.write_str(name),
            VarKind::Array(name) => write!(f, "{name} array"),
        }
    }
}

/// The FMI 3.0 variable elements, each with what it reads as. Names are `'static` so that
/// [`VarKind`] stays `Copy`.
const FMI3_TYPES: [(&str, VarKind); 15] = [
    ("Float64", VarKind::Real),
    ("Int32", VarKind::Integer),
    ("Boolean", VarKind::Boolean),
    ("String", VarKind::String),
    ("Enumeration", VarKind::Enumeration),
    ("Float32", VarKind::Other("Float32")),
    ("Int8", VarKind::Other("Int8")),
    ("UInt8", VarKind::Other("UInt8")),
    ("Int16", VarKind::Other("Int16")),
    ("UInt16", VarKind::Other("UInt16")),
    ("UInt32", VarKind::Other("UInt32")),
    ("Int64", VarKind::Other("Int64")),
    ("UInt64", VarKind::Other("UInt64")),
    ("Binary", VarKind::Other("Binary")),
    ("Clock", VarKind::Other("Clock")),
];

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
        let fmi3 = is_fmi3(&fmi_version);
        if fmi_version != "2.0" && !fmi3 {
            return Err(FmuError::UnsupportedVersion {
                version: fmi_version,
            });
        }
        // FMI 3.0 writes "FMUState" where FMI 2.0 wrote "FMUstate".
        let (get_set, serialize) = if fmi3 {
            ("canGetAndSetFMUState", "canSerializeFMUState")
        } else {
            ("canGetAndSetFMUstate", "canSerializeFMUstate")
        };
        let co_simulation = match child(root, "CoSimulation") {
            None => None,
            Some(cs) => Some(CoSimulation {
                model_identifier: required(cs, "modelIdentifier")?.to_string(),
                can_get_and_set_fmu_state: flag(cs, get_set)?,
                can_serialize_fmu_state: flag(cs, serialize)?,
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
            Some(mv) if fmi3 => mv
                .children()
                .filter(|n| n.is_element())
                .enumerate()
                .map(|(i, n)| variable3(i, n))
                .collect::<Result<_, _>>()?,
            Some(mv) => mv
                .children()
                .filter(|n| n.has_tag_name("ScalarVariable"))
                .enumerate()
                .map(|(i, n)| variable(i, n))
                .collect::<Result<_, _>>()?,
        };
        unique_names(&variables)?;
        let token = if fmi3 { "instantiationToken" } else { "guid" };
        Ok(ModelDescription {
            fmi_version,
            model_name: required(root, "modelName")?.to_string(),
            guid: required(root, token)?.to_string(),
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

    /// Whether this is an FMI 3.0 description (`fmiVersion` `3.0` or `3.0.x`).
    pub fn is_fmi3(&self) -> bool {
        is_fmi3(&self.fmi_version)
    }
}

/// `3.0` and its maintenance releases (`3.0.1`); FMPy reads the same set.
fn is_fmi3(version: &str) -> bool {
    version == "3.0" || version.starts_with("3.0.")
}

/// A variable element's `name` and `valueReference` (both versions): a missing name is
/// told at `name_at` (the element by position), a bad reference by the element's
/// `element` and name.
fn name_and_reference(n: Node, name_at: &str, element: &str) -> Result<(String, u32), FmuError> {
    let name = n
        .attribute("name")
        .ok_or_else(|| bad(name_at, "missing".into()))?
        .to_string();
    let at = format!("{element} '{name}'@valueReference");
    let vr = n
        .attribute("valueReference")
        .ok_or_else(|| bad(&at, "missing".into()))?;
    let value_reference = vr
        .trim()
        .parse::<u32>()
        .map_err(|_| bad(&at, format!("'{vr}' is not a 32-bit unsigned integer")))?;
    Ok((name, value_reference))
}

/// Reads the `index`-th (0-based) `<ScalarVariable>`.
fn variable(index: usize, n: Node) -> Result<ScalarVariable, FmuError> {
    let at = |attr: &str| format!("ScalarVariable[{}]@{attr}", index + 1);
    let (name, value_reference) = name_and_reference(n, &at("name"), "ScalarVariable")?;
    let at = |attr: &str| format!("ScalarVariable '{name}'@{attr}");
    let causality = causality(n, &at("causality"), false)?;
    let variability = variability(n, &at("variability"), "continuous")?;
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
    let start = start(kind, ty.attribute("start"), &field)?;
    Ok(ScalarVariable {
        name,
        value_reference,
        causality,
        variability,
        kind,
        start,
    })
}

/// Reads the `index`-th (0-based) variable element of an FMI 3.0 `<ModelVariables>`.
fn variable3(index: usize, n: Node) -> Result<ScalarVariable, FmuError> {
    let element = n.tag_name().name();
    let at = |attr: &str| format!("ModelVariables/{element}[{}]@{attr}", index + 1);
    let Some(&(type_name, kind)) = FMI3_TYPES.iter().find(|(t, _)| *t == element) else {
        return Err(bad(
            &format!("ModelVariables/{element}[{}]", index + 1),
            format!("unknown variable element <{element}>"),
        ));
    };
    let (name, value_reference) = name_and_reference(n, &at("name"), element)?;
    let at = |attr: &str| format!("{element} '{name}'@{attr}");
    let causality = causality(n, &at("causality"), true)?;
    let default = if matches!(type_name, "Float64" | "Float32") {
        "continuous"
    } else {
        "discrete"
    };
    let variability = variability(n, &at("variability"), default)?;
    let kind = if n.children().any(|c| c.has_tag_name("Dimension")) {
        VarKind::Array(type_name)
    } else {
        kind
    };
    let start = start(kind, n.attribute("start"), &at("start"))?;
    Ok(ScalarVariable {
        name,
        value_reference,
        causality,
        variability,
        kind,
        start,
    })
}

/// The `causality` attribute of `n` (`field` names it in errors); `structuralParameter`
/// only where `fmi3`.
fn causality(n: Node, field: &str, fmi3: bool) -> Result<Causality, FmuError> {
    Ok(match n.attribute("causality").unwrap_or("local") {
        "parameter" => Causality::Parameter,
        "calculatedParameter" => Causality::CalculatedParameter,
        "input" => Causality::Input,
        "output" => Causality::Output,
        "local" => Causality::Local,
        "independent" => Causality::Independent,
        "structuralParameter" if fmi3 => Causality::StructuralParameter,
        other => return Err(bad(field, format!("unknown value '{other}'"))),
    })
}

/// The `variability` attribute of `n`, `default` when absent.
fn variability(n: Node, field: &str, default: &str) -> Result<Variability, FmuError> {
    Ok(match n.attribute("variability").unwrap_or(default) {
        "constant" => Variability::Constant,
        "fixed" => Variability::Fixed,
        "tunable" => Variability::Tunable,
        "discrete" => Variability::Discrete,
        "continuous" => Variability::Continuous,
        other => return Err(bad(field, format!("unknown value '{other}'"))),
    })
}

/// A `start` attribute as a number for `kind` (see [`ScalarVariable::start`]).
fn start(kind: VarKind, text: Option<&str>, field: &str) -> Result<Option<f64>, FmuError> {
    Ok(match (kind, text) {
        (_, None) | (VarKind::String | VarKind::Other(_) | VarKind::Array(_), _) => None,
        (VarKind::Boolean, Some(s)) => Some(match s.trim() {
            "true" | "1" => 1.0,
            "false" | "0" => 0.0,
            _ => return Err(bad(field, format!("'{s}' is not a boolean"))),
        }),
        (VarKind::Real, Some(s)) => Some(
            s.trim()
                .parse::<f64>()
                .map_err(|_| bad(field, format!("'{s}' is not a number")))?,
        ),
        (VarKind::Integer | VarKind::Enumeration, Some(s)) => Some(
            s.trim()
                .parse::<i32>()
                .map_err(|_| bad(field, format!("'{s}' is not a 32-bit integer")))?
                .into(),
        ),
    })
}

/// A description error for `field`.
/// Every variable's name is its own (FMI 2.0 §2.2.7, FMI 3.0 §2.4.7: names are unique):
/// two variables of one name are refused naming both, by their positions under
/// `<ModelVariables>` (1-based, document order, as FMI 2.0's `index` counts), since a
/// connection, a start value or a trace column naming it could mean either.
fn unique_names(variables: &[ScalarVariable]) -> Result<(), FmuError> {
    let mut seen: std::collections::HashMap<&str, usize> =
        std::collections::HashMap::with_capacity(variables.len());
    for (i, v) in variables.iter().enumerate() {
        if let Some(first) = seen.insert(&v.name, i) {
            return Err(bad(
                "ModelVariables",
                format!(
                    "variables {} and {} (1-based, in document order) are both named {:?}; \
                     a variable's name must be unique",
                    first + 1,
                    i + 1,
                    v.name
                ),
            ));
        }
    }
    Ok(())
}

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

    #[test]
    fn two_variables_of_one_name_are_refused_naming_both() {
        let xml = MINIMAL.replace("name=\"s\"", "name=\"k\"");
        let err = ModelDescription::parse(&xml).err().map(|e| e.to_string());
        assert_eq!(
            err.as_deref(),
            Some(
                "modelDescription.xml: ModelVariables: variables 1 and 3 (1-based, in document \
                 order) are both named \"k\"; a variable's name must be unique"
            )
        );
        let fmi3 = r#"<fmiModelDescription fmiVersion="3.0" modelName="m" instantiationToken="{t}">
  <CoSimulation modelIdentifier="m"/>
  <ModelVariables>
    <Float64 name="time" valueReference="0" causality="independent" variability="continuous"/>
    <Float64 name="y" valueReference="1" causality="output" variability="continuous"/>
    <Int32 name="y" valueReference="2" causality="output" variability="discrete"/>
  </ModelVariables>
</fmiModelDescription>"#;
        let err = ModelDescription::parse(fmi3).err().map(|e| e.to_string());
        let err = err.unwrap_or_default();
        assert!(
            err.contains("variables 2 and 3") && err.contains("\"y\""),
            "{err}"
        );
    }
}
