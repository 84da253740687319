//! Generates the Rust view of `modelDescription.xml` (the single source of truth for variable
//! names, value references, start values and ranges) and checks the file's guid.
//!
//! Output `$OUT_DIR/model_description.rs`: `GUID`, `MODEL_IDENTIFIER`, the table `VARS` (one
//! entry per scalar variable, in file order) and, in `mod var`, one `usize` constant per variable
//! named exactly like it (its position in `VARS`); likewise `CATEGORIES` and `mod cat` for the
//! log categories; `STATES` and `DERIVATIVES` (the continuous states and their derivatives, in
//! ModelStructure/Derivatives order) and `EVENT_INDICATORS` (the variables named by the vendor
//! annotation, `numberOfEventIndicators` of them) for Model Exchange.
//! Renaming or removing a variable the Rust code uses is then a compile error.
//!
//! Output `$OUT_DIR/fmi3_model_description.xml`: the FMI 3.0 model description, generated from the
//! same file (see `build_fmi3.rs`); the FMI 3.0 FMU has no variable list of its own.

use std::collections::BTreeSet;
use std::fmt::Write as _;
use std::path::PathBuf;

use sha2::{Digest, Sha256};

#[path = "build_fmi3.rs"]
mod fmi3;

const KEY: &str = "guid=\"";

/// Same rule as `fmu/guid.py`: SHA-256 of the file with the guid value emptied, first 16 bytes.
fn derive_guid(text: &str) -> Result<(String, String), String> {
    let start = text.find(KEY).ok_or("no guid attribute")? + KEY.len();
    let end = start + text[start..].find('"').ok_or("unterminated guid")?;
    let mut h = Sha256::new();
    h.update(&text.as_bytes()[..start]);
    h.update(&text.as_bytes()[end..]);
    let hex: String = h.finalize()[..16]
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect();
    let guid = format!(
        "{{{}-{}-{}-{}-{}}}",
        &hex[..8],
        &hex[8..12],
        &hex[12..16],
        &hex[16..20],
        &hex[20..]
    );
    Ok((guid, text[start..end].to_string()))
}

fn num(node: roxmltree::Node, attr: &str, default: f64) -> Result<f64, String> {
    node.attribute(attr).map_or(Ok(default), |s| {
        s.trim()
            .parse::<f64>()
            .map_err(|e| format!("{attr}=\"{s}\": {e}"))
    })
}

/// `v` as a Rust expression.
fn lit(v: f64) -> String {
    match v {
        f64::INFINITY => "f64::INFINITY".into(),
        f64::NEG_INFINITY => "f64::NEG_INFINITY".into(),
        _ => format!("{v:?}"),
    }
}

fn generate(text: &str) -> Result<String, String> {
    let (guid, stated) = derive_guid(text)?;
    if guid != stated {
        return Err(format!(
            "modelDescription.xml holds guid {stated} but its content gives {guid}: run `make fmu-guid`"
        ));
    }
    let doc = roxmltree::Document::parse(text).map_err(|e| e.to_string())?;
    let root = doc.root_element();
    let cs = root
        .children()
        .find(|n| n.has_tag_name("CoSimulation"))
        .ok_or("no CoSimulation element")?;
    let ident = cs
        .attribute("modelIdentifier")
        .ok_or("no modelIdentifier")?;
    let me = root
        .children()
        .find(|n| n.has_tag_name("ModelExchange"))
        .ok_or("no ModelExchange element")?;
    if me.attribute("modelIdentifier") != Some(ident) {
        return Err("ModelExchange and CoSimulation must share the modelIdentifier".into());
    }
    let indicators = num(root, "numberOfEventIndicators", 0.0)?;

    // Enumeration types: name -> (min item value, max item value).
    let mut enums = std::collections::HashMap::new();
    for t in root.descendants().filter(|n| n.has_tag_name("SimpleType")) {
        if let Some(e) = t.children().find(|n| n.has_tag_name("Enumeration")) {
            let vals: Vec<f64> = e
                .children()
                .filter(|n| n.has_tag_name("Item"))
                .map(|n| num(n, "value", f64::NAN))
                .collect::<Result<_, _>>()?;
            let lo = vals.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = vals.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            enums.insert(
                t.attribute("name").unwrap_or_default().to_string(),
                (lo, hi),
            );
        }
    }

    let mut out = String::new();
    let mut consts = String::new();
    let mut vrs = BTreeSet::new();
    let mut outputs = Vec::new();
    // (index of the derivative, index of its state), 1-based.
    let mut derivatives = Vec::new();
    let mut continuous_reals = BTreeSet::new();
    let vars = root
        .descendants()
        .filter(|n| n.has_tag_name("ScalarVariable"));
    writeln!(out, "/// Variables of modelDescription.xml, in file order.").unwrap();
    writeln!(out, "pub static VARS: &[Var] = &[").unwrap();
    for (i, v) in vars.enumerate() {
        let name = v.attribute("name").ok_or("variable without name")?;
        let vr: u32 = v
            .attribute("valueReference")
            .ok_or("no valueReference")?
            .parse()
            .map_err(|e| format!("{name}: valueReference: {e}"))?;
        if !vrs.insert(vr) {
            return Err(format!("{name}: duplicate valueReference {vr}"));
        }
        let causality = match v.attribute("causality").unwrap_or("local") {
            "parameter" => "Parameter",
            "input" => "Input",
            "output" => "Output",
            "local" => "Local",
            "independent" => "Independent",
            other => return Err(format!("{name}: causality {other} not handled")),
        };
        if causality == "Output" {
            outputs.push(i + 1);
        }
        let tunable = v.attribute("variability") == Some("tunable");
        let ty = v
            .children()
            .find(|n| n.is_element())
            .ok_or(format!("{name}: no type element"))?;
        let enumeration = ty.tag_name().name() == "Enumeration";
        let (kind, lo, hi) = match ty.tag_name().name() {
            "Real" => ("Real", f64::NEG_INFINITY, f64::INFINITY),
            "Integer" => ("Integer", f64::from(i32::MIN), f64::from(i32::MAX)),
            "Boolean" => ("Boolean", 0.0, 1.0),
            "Enumeration" => {
                let t = ty.attribute("declaredType").unwrap_or_default();
                let (lo, hi) = enums
                    .get(t)
                    .copied()
                    .ok_or(format!("{name}: unknown type {t}"))?;
                ("Integer", lo, hi)
            }
            other => return Err(format!("{name}: type {other} not handled")),
        };
        let start = match ty.attribute("start") {
            Some("true") => 1.0,
            Some("false") => 0.0,
            _ => num(ty, "start", 0.0)?,
        };
        let (min, max) = (num(ty, "min", lo)?, num(ty, "max", hi)?);
        if !(min <= start && start <= max) {
            return Err(format!("{name}: start {start} outside [{min}, {max}]"));
        }
        let unit = ty.attribute("unit").unwrap_or("");
        let continuous = v.attribute("variability").unwrap_or("continuous") == "continuous";
        if kind == "Real" && continuous {
            continuous_reals.insert(i + 1);
        }
        if let Some(d) = ty.attribute("derivative") {
            let of: usize = d
                .parse()
                .map_err(|e| format!("{name}: derivative=\"{d}\": {e}"))?;
            derivatives.push((i + 1, of));
        }
        writeln!(
            out,
            "    Var {{ name: {name:?}, vr: {vr}, kind: Kind::{kind}, causality: Causality::{causality}, \
             tunable: {tunable}, enumeration: {enumeration}, start: {}, min: {}, max: {}, unit: {unit:?} }},",
            lit(start),
            lit(min),
            lit(max)
        )
        .unwrap();
        writeln!(consts, "    pub const {name}: usize = {i};").unwrap();
    }
    writeln!(out, "];").unwrap();

    // ModelStructure: Outputs lists every output, Derivatives every variable with a
    // `derivative` attribute (in file order), InitialUnknowns both (ascending, no repeats).
    // A derivative is of a continuous Real and a state has one derivative.
    let states: Vec<usize> = derivatives.iter().map(|&(_, of)| of).collect();
    if let Some(&(d, of)) = derivatives
        .iter()
        .find(|&&(d, of)| !continuous_reals.contains(&d) || !continuous_reals.contains(&of))
    {
        return Err(format!(
            "variable {d} is the derivative of {of}: both must be continuous Reals"
        ));
    }
    if states.iter().collect::<BTreeSet<_>>().len() != states.len() {
        return Err(format!("a state has two derivatives: {derivatives:?}"));
    }
    if indicators.fract() != 0.0 || !(0.0..=64.0).contains(&indicators) {
        return Err(format!("numberOfEventIndicators = {indicators}"));
    }
    let indicator_vars = event_indicators(root)?;
    if indicator_vars.len() != indicators as usize {
        return Err(format!(
            "numberOfEventIndicators = {indicators} but the vendor annotation names {} indicators",
            indicator_vars.len()
        ));
    }
    let all: Vec<roxmltree::Node> = root
        .descendants()
        .filter(|n| n.has_tag_name("ScalarVariable"))
        .collect();
    let mut indicator_positions = Vec::new();
    for name in &indicator_vars {
        let i = all
            .iter()
            .position(|v| v.attribute("name") == Some(name))
            .ok_or(format!("event indicator {name} is not a variable"))?;
        if !continuous_reals.contains(&(i + 1)) || all[i].attribute("causality") != Some("local") {
            return Err(format!(
                "event indicator {name} must be a local continuous Real"
            ));
        }
        indicator_positions.push(i + 1);
    }
    let ders: Vec<usize> = derivatives.iter().map(|&(d, _)| d).collect();
    let initial: Vec<usize> = outputs
        .iter()
        .chain(&ders)
        .copied()
        .collect::<BTreeSet<_>>()
        .into_iter()
        .collect();
    for (section, expected) in [
        ("Outputs", &outputs),
        ("Derivatives", &ders),
        ("InitialUnknowns", &initial),
    ] {
        let listed: Vec<usize> = root
            .descendants()
            .filter(|n| n.has_tag_name(section))
            .flat_map(|n| n.children().filter(|c| c.has_tag_name("Unknown")))
            .map(|u| num(u, "index", 0.0).map(|x| x as usize))
            .collect::<Result<_, _>>()?;
        if &listed != expected {
            return Err(format!(
                "ModelStructure/{section} lists {listed:?}, expected {expected:?}"
            ));
        }
    }
    let positions = |v: &[usize]| {
        v.iter()
            .map(|i| (i - 1).to_string())
            .collect::<Vec<_>>()
            .join(", ")
    };

    let mut cats = String::new();
    let mut cat_consts = String::new();
    let names = root
        .descendants()
        .filter(|n| n.has_tag_name("Category"))
        .map(|n| n.attribute("name").ok_or("category without name"));
    for (i, name) in names.enumerate() {
        let name = name?;
        write!(cats, "{name:?}, ").unwrap();
        writeln!(cat_consts, "    pub const {name}: usize = {i};").unwrap();
    }

    let mut code = String::new();
    writeln!(
        code,
        "/// Derived from modelDescription.xml (see fmu/guid.py)."
    )
    .unwrap();
    writeln!(code, "pub const GUID: &str = {guid:?};").unwrap();
    writeln!(
        code,
        "/// `modelIdentifier` of the ModelExchange and CoSimulation elements."
    )
    .unwrap();
    writeln!(code, "pub const MODEL_IDENTIFIER: &str = {ident:?};").unwrap();
    code.push_str(&out);
    writeln!(
        code,
        "/// Continuous states (positions in [`VARS`]), in ModelStructure/Derivatives order."
    )
    .unwrap();
    writeln!(
        code,
        "pub static STATES: &[usize] = &[{}];",
        positions(&states)
    )
    .unwrap();
    writeln!(code, "/// Their derivatives (positions in [`VARS`]).").unwrap();
    writeln!(
        code,
        "pub static DERIVATIVES: &[usize] = &[{}];",
        positions(&ders)
    )
    .unwrap();
    writeln!(
        code,
        "/// The event indicators (positions in [`VARS`]), `numberOfEventIndicators` of them."
    )
    .unwrap();
    writeln!(
        code,
        "pub static EVENT_INDICATORS: &[usize] = &[{}];",
        positions(&indicator_positions)
    )
    .unwrap();
    writeln!(
        code,
        "/// Position of each variable in [`VARS`], named like the variable."
    )
    .unwrap();
    writeln!(
        code,
        "#[allow(non_upper_case_globals, dead_code)]\npub mod var {{"
    )
    .unwrap();
    code.push_str(&consts);
    writeln!(code, "}}").unwrap();
    writeln!(code, "/// Log categories, in file order.").unwrap();
    writeln!(code, "pub static CATEGORIES: &[&str] = &[{cats}];").unwrap();
    writeln!(code, "/// Position of each log category in [`CATEGORIES`].").unwrap();
    writeln!(
        code,
        "#[allow(non_upper_case_globals, dead_code)]\npub mod cat {{"
    )
    .unwrap();
    code.push_str(&cat_consts);
    writeln!(code, "}}").unwrap();
    Ok(code)
}

/// Names of the event-indicator variables, from
/// `VendorAnnotations/Tool[@name="bistable-impact"]/EventIndicators/Indicator`.
fn event_indicators(root: roxmltree::Node) -> Result<Vec<String>, String> {
    let tool = root
        .descendants()
        .filter(|n| n.has_tag_name("Tool"))
        .find(|n| n.attribute("name") == Some("bistable-impact"));
    let Some(tool) = tool else {
        return Ok(Vec::new());
    };
    tool.descendants()
        .filter(|n| n.has_tag_name("Indicator"))
        .map(|n| {
            n.attribute("name")
                .map(str::to_string)
                .ok_or_else(|| "Indicator without name".to_string())
        })
        .collect()
}

fn main() {
    let xml = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").unwrap())
        .join("..")
        .join("modelDescription.xml");
    println!("cargo:rerun-if-changed={}", xml.display());
    let text = std::fs::read_to_string(&xml)
        .unwrap_or_else(|e| panic!("cannot read {}: {e}", xml.display()));
    let out = PathBuf::from(std::env::var("OUT_DIR").unwrap());
    match generate(&text) {
        Ok(code) => std::fs::write(out.join("model_description.rs"), code)
            .expect("write model_description.rs"),
        Err(e) => panic!("modelDescription.xml: {e}"),
    }
    match fmi3::generate(&text) {
        Ok(xml) => std::fs::write(out.join("fmi3_model_description.xml"), xml)
            .expect("write fmi3_model_description.xml"),
        Err(e) => panic!("modelDescription.xml (FMI 3.0 view): {e}"),
    }
}
