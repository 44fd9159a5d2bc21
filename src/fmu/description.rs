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
//! FMI 3.0 types map onto [`VarKind`]: Float64 → `Real` and Int32 → `Integer` (the ABI
//! forms of FMI 2.0's Real and Integer), every other type to its own variant;
//! [`ScalarVariable::type_name`] keeps the element's name for messages. An array
//! variable (with `<Dimension>` children) keeps them in [`ScalarVariable::dimensions`];
//! [`ModelDescription::shape`] resolves its size, from a structural parameter's start
//! value where a dimension names one.

use roxmltree::{Document, Node};

use super::value::{parse_hex, Value};
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
    /// The type's element name as the description writes it (`Real`, `Integer` in FMI
    /// 2.0; `Float64`, `Int32`, `UInt64` in FMI 3.0), for messages.
    pub type_name: &'static str,
    /// FMI 3.0: the `<Dimension>` children of an array variable, outermost first; empty
    /// for a scalar (and every FMI 2.0 variable).
    pub dimensions: Vec<Dimension>,
    /// `start` of a scalar in its type's form (FMI 3.0 String and Binary: the first
    /// `<Start value>`, a Binary's as hex bytes); `None` when absent, for a Clock and
    /// for an array.
    pub start: Option<Value>,
}

/// One `<Dimension>` of an FMI 3.0 array variable.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Dimension {
    /// `start`: a fixed size.
    Fixed(u64),
    /// `valueReference`: the size is the value of that (structural) parameter, read
    /// from its start value since dsmcosim does not enter configuration mode.
    Parameter(u32),
}

/// Largest number of elements of an array variable dsmcosim reads (the product of its
/// dimensions): 65 536, checked before anything is allocated for it.
pub const MAX_ARRAY_ELEMENTS: u64 = 1 << 16;

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

/// The variable's type. FMI 2.0's and FMI 3.0's types of one ABI form share a variant:
/// Real and Float64 ([`VarKind::Real`]), Integer and Int32 ([`VarKind::Integer`]);
/// [`ScalarVariable::type_name`] keeps the element name.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
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
    /// `<Float32>` (FMI 3.0).
    Float32,
    /// `<Int8>` (FMI 3.0).
    Int8,
    /// `<UInt8>` (FMI 3.0).
    UInt8,
    /// `<Int16>` (FMI 3.0).
    Int16,
    /// `<UInt16>` (FMI 3.0).
    UInt16,
    /// `<UInt32>` (FMI 3.0).
    UInt32,
    /// `<Int64>` (FMI 3.0).
    Int64,
    /// `<UInt64>` (FMI 3.0).
    UInt64,
    /// `<Binary>` (FMI 3.0): bytes.
    Binary,
    /// `<Clock>` (FMI 3.0): not read (it needs event mode).
    Clock,
}

impl VarKind {
    /// The FMI 3.0 element name of the type (`Float64`, `Int32`), as the FMI 3.0
    /// functions name it (`fmi3GetInt32`).
    pub fn fmi3_name(self) -> &'static str {
        match self {
            VarKind::Real => "Float64",
            VarKind::Integer => "Int32",
            VarKind::Boolean => "Boolean",
            VarKind::String => "String",
            VarKind::Enumeration => "Enumeration",
            VarKind::Float32 => "Float32",
            VarKind::Int8 => "Int8",
            VarKind::UInt8 => "UInt8",
            VarKind::Int16 => "Int16",
            VarKind::UInt16 => "UInt16",
            VarKind::UInt32 => "UInt32",
            VarKind::Int64 => "Int64",
            VarKind::UInt64 => "UInt64",
            VarKind::Binary => "Binary",
            VarKind::Clock => "Clock",
        }
    }

    /// Whether values of this type are numbers (or Booleans): what a cost, a plot and a
    /// connection take. Not String, Binary or Clock.
    pub fn is_numeric(self) -> bool {
        !matches!(self, VarKind::String | VarKind::Binary | VarKind::Clock)
    }
}

impl std::fmt::Display for VarKind {
    /// FMI 2.0's names for the types it has (`Real`, `Integer`, …), FMI 3.0's for the
    /// others (`Float32`, `UInt64`); a variable's own element name is
    /// [`ScalarVariable::type_name`].
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            VarKind::Real => f.write_str("Real"),
            VarKind::Integer => f.write_str("Integer"),
            other => f.write_str(other.fmi3_name()),
        }
    }
}

/// The FMI 3.0 variable elements, each with what it reads as.
const FMI3_TYPES: [(&str, VarKind); 15] = [
    ("Float64", VarKind::Real),
    ("Int32", VarKind::Integer),
    ("Boolean", VarKind::Boolean),
    ("String", VarKind::String),
    ("Enumeration", VarKind::Enumeration),
    ("Float32", VarKind::Float32),
    ("Int8", VarKind::Int8),
    ("UInt8", VarKind::UInt8),
    ("Int16", VarKind::Int16),
    ("UInt16", VarKind::UInt16),
    ("UInt32", VarKind::UInt32),
    ("Int64", VarKind::Int64),
    ("UInt64", VarKind::UInt64),
    ("Binary", VarKind::Binary),
    ("Clock", VarKind::Clock),
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

    /// The size of each dimension of `v` (empty for a scalar), outermost first: a
    /// `<Dimension start>` as written, a `<Dimension valueReference>` as the start value
    /// of the variable it names (a structural parameter, whose value dsmcosim does not
    /// change). Refused, naming the variable, when that variable is missing or has no
    /// whole start value, or when the element count exceeds [`MAX_ARRAY_ELEMENTS`]
    /// (checked before anything is allocated).
    pub fn shape(&self, v: &ScalarVariable) -> Result<Vec<usize>, FmuError> {
        let field = format!("{} '{}'/Dimension", v.type_name, v.name);
        let mut shape = Vec::with_capacity(v.dimensions.len());
        let mut count: u64 = 1;
        for d in &v.dimensions {
            let n = match *d {
                Dimension::Fixed(n) => n,
                Dimension::Parameter(vr) => {
                    let Some(p) = self.variables.iter().find(|p| p.value_reference == vr) else {
                        return Err(bad(
                            &field,
                            format!("valueReference {vr} names no variable"),
                        ));
                    };
                    match &p.start {
                        Some(Value::UInt(n)) => *n,
                        Some(Value::Int(n)) if *n >= 0 => *n as u64,
                        _ => {
                            return Err(bad(
                                &field,
                                format!(
                                    "its size is {} '{}' (valueReference {vr}), which has no \
                                     whole non-negative start value",
                                    p.type_name, p.name
                                ),
                            ))
                        }
                    }
                }
            };
            count = count
                .checked_mul(n)
                .filter(|&c| c <= MAX_ARRAY_ELEMENTS)
                .ok_or_else(|| {
                    bad(
                        &field,
                        format!(
                            "more than MAX_ARRAY_ELEMENTS = {MAX_ARRAY_ELEMENTS} elements \
                             (a dimension of {n})"
                        ),
                    )
                })?;
            shape.push(n as usize);
        }
        Ok(shape)
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
    let (kind, type_name) = match ty.tag_name().name() {
        "Real" => (VarKind::Real, "Real"),
        "Integer" => (VarKind::Integer, "Integer"),
        "Boolean" => (VarKind::Boolean, "Boolean"),
        "String" => (VarKind::String, "String"),
        "Enumeration" => (VarKind::Enumeration, "Enumeration"),
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
        type_name,
        dimensions: Vec::new(),
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
    let dimensions = n
        .children()
        .filter(|c| c.has_tag_name("Dimension"))
        .map(|d| dimension(d, &at("Dimension")))
        .collect::<Result<Vec<_>, _>>()?;
    // A String's or a Binary's start values are `<Start value>` children (one per
    // element), as FMI 3.0's schema has them.
    let text = if matches!(kind, VarKind::String | VarKind::Binary) {
        n.children()
            .find(|c| c.has_tag_name("Start"))
            .and_then(|c| c.attribute("value"))
    } else {
        n.attribute("start")
    };
    let start = if dimensions.is_empty() {
        start(kind, text, &at("start"))?
    } else {
        None
    };
    Ok(ScalarVariable {
        name,
        value_reference,
        causality,
        variability,
        kind,
        type_name,
        dimensions,
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

/// A `<Dimension>`: its `start` (a fixed size) or its `valueReference` (the variable
/// holding the size), exactly one of them.
fn dimension(d: Node, field: &str) -> Result<Dimension, FmuError> {
    match (d.attribute("start"), d.attribute("valueReference")) {
        (Some(s), None) => s
            .trim()
            .parse::<u64>()
            .map(Dimension::Fixed)
            .map_err(|_| bad(field, format!("start '{s}' is not a size"))),
        (None, Some(r)) => r
            .trim()
            .parse::<u32>()
            .map(Dimension::Parameter)
            .map_err(|_| {
                bad(
                    field,
                    format!("valueReference '{r}' is not a value reference"),
                )
            }),
        _ => Err(bad(
            field,
            "needs exactly one of start and valueReference".into(),
        )),
    }
}

/// A scalar's `start` text in `kind`'s form (see [`ScalarVariable::start`]): integers
/// within their type's range, Booleans `true`/`false`/`1`/`0`, Binary as hex.
pub(crate) fn start(
    kind: VarKind,
    text: Option<&str>,
    field: &str,
) -> Result<Option<Value>, FmuError> {
    let Some(s) = text else {
        return Ok(None);
    };
    let t = s.trim();
    let int = |lo: i64, hi: i64| -> Result<Value, FmuError> {
        t.parse::<i64>()
            .ok()
            .filter(|i| (lo..=hi).contains(i))
            .map(Value::Int)
            .ok_or_else(|| bad(field, format!("'{s}' is not a {kind} (from {lo} to {hi})")))
    };
    let uint = |hi: u64| -> Result<Value, FmuError> {
        t.parse::<u64>()
            .ok()
            .filter(|u| *u <= hi)
            .map(Value::UInt)
            .ok_or_else(|| bad(field, format!("'{s}' is not a {kind} (from 0 to {hi})")))
    };
    Ok(Some(match kind {
        VarKind::Clock => return Ok(None),
        VarKind::Real => Value::Float(
            t.parse::<f64>()
                .map_err(|_| bad(field, format!("'{s}' is not a number")))?,
        ),
        VarKind::Float32 => Value::Float32(
            t.parse::<f32>()
                .map_err(|_| bad(field, format!("'{s}' is not a number")))?,
        ),
        VarKind::Boolean => Value::Bool(match t {
            "true" | "1" => true,
            "false" | "0" => false,
            _ => return Err(bad(field, format!("'{s}' is not a boolean"))),
        }),
        VarKind::String => Value::Text(s.to_string()),
        VarKind::Binary => Value::Bytes(parse_hex(s).map_err(|e| bad(field, e))?),
        VarKind::Integer => int(i32::MIN.into(), i32::MAX.into())?,
        // FMI 2.0 passes enumerations as an int, FMI 3.0 as an Int64.
        VarKind::Enumeration | VarKind::Int64 => int(i64::MIN, i64::MAX)?,
        VarKind::Int8 => int(i8::MIN.into(), i8::MAX.into())?,
        VarKind::Int16 => int(i16::MIN.into(), i16::MAX.into())?,
        VarKind::UInt8 => uint(u8::MAX.into())?,
        VarKind::UInt16 => uint(u16::MAX.into())?,
        VarKind::UInt32 => uint(u32::MAX.into())?,
        VarKind::UInt64 => uint(u64::MAX)?,
    }))
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
        assert_eq!(on.and_then(|v| v.start.clone()), Some(Value::Bool(true)));
        assert_eq!(
            d.variable("k").and_then(|v| v.start.clone()),
            Some(Value::Float(4.0))
        );
        assert_eq!(
            d.variable("s").map(|v| (v.kind, v.start.clone())),
            Some((VarKind::String, Some(Value::Text("x".into()))))
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
