//! The FMI 3.0 model description, generated from the FMI 2.0 `modelDescription.xml` (the single
//! source of truth): same variables, value references, units, start values, ranges, log
//! categories and default experiment, in FMI 3.0's schema. Types: Real → Float64, Integer →
//! Int32, Boolean → Boolean, Enumeration → Enumeration (read and written as Int64). The
//! `instantiationToken` is the FMI 2.0 guid (both files are one model). The FMI 3.0 capability
//! flags that have no FMI 2.0 counterpart state what `fmu/src/exports3.rs` implements.

use std::fmt::Write as _;

use roxmltree::Node;

/// `s` with the XML special characters escaped (for attribute values).
fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// The FMI 3.0 texts of descriptions that speak of FMI 2.0: `(key, FMI 2.0 part, FMI 3.0
/// part)`, the key a variable's name, `Type.item` for an enumeration item or `Type` for a type.
/// The FMI 2.0 part must be in the description (a changed source fails the build), and no
/// FMI 3.0 description may name FMI 2.0 functions (`fmi2...`) or speak of input derivatives,
/// which FMI 3.0 does not have.
const FMI3_TEXTS: &[(&str, &str, &str)] = &[
    (
        "z_in",
        "(FMI 2.0 co-simulation: derivatives of order 2..5 through fmi2SetRealInputDerivatives \
         extend the plate polynomial over the step; order 1 is zdot_in)",
        "(FMI 3.0 has no input derivatives: between communication points the plate follows \
         the samples as plate_reconstruction says)",
    ),
    (
        "zdot_in",
        "(FMI 2.0 co-simulation: its derivatives of order 1..4 are plate derivatives of order \
         2..5)",
        "(FMI 3.0 has no input derivatives: between communication points the plate follows \
         the samples as plate_reconstruction says)",
    ),
    (
        "ShakerMode.external",
        "the inputs z_in, zdot_in and their derivatives",
        "the inputs z_in, zdot_in",
    ),
    (
        "PlateReconstruction",
        "in external mode when the host gives no input derivatives",
        "in external mode (FMI 3.0 has no input derivatives)",
    ),
    (
        "plate_reconstruction",
        "external mode without input derivatives: how the plate is rebuilt from the sampled \
         z_in, zdot_in (input derivatives, when given for a step, take precedence)",
        "external mode: how the plate is rebuilt from the sampled z_in, zdot_in (FMI 3.0 has \
         no input derivatives)",
    ),
    (
        "PlateReconstruction.taylor",
        "z_in + zdot_in*s (plus any derivatives given)",
        "z_in + zdot_in*s",
    ),
];

/// ` description="..."` of `node` (none without one) with its FMI 3.0 text ([`FMI3_TEXTS`]).
fn description3(node: Node, key: &str) -> Result<String, String> {
    let Some(text) = node.attribute("description") else {
        return Ok(String::new());
    };
    let mut text = text.to_string();
    for &(k, two, three) in FMI3_TEXTS.iter().filter(|e| e.0 == key) {
        if !text.contains(two) {
            return Err(format!(
                "{k}: its FMI 3.0 text in build_fmi3.rs replaces '{two}', which its description \
                 no longer has"
            ));
        }
        text = text.replace(two, three);
    }
    let lower = text.to_lowercase();
    if lower.contains("fmi2") || (lower.contains("input derivative") && !lower.contains("no input"))
    {
        return Err(format!(
            "{key}: the description speaks of FMI 2.0 ('{text}'); give its FMI 3.0 text in \
             FMI3_TEXTS (build_fmi3.rs)"
        ));
    }
    Ok(format!(" description=\"{}\"", esc(&text)))
}

/// ` name="value"` for each attribute of `node` in `names` that is present, renamed by `map`.
fn copy_attrs(node: Node, names: &[(&str, &str)]) -> String {
    let mut out = String::new();
    for &(from, to) in names {
        if let Some(v) = node.attribute(from) {
            write!(out, " {to}=\"{}\"", esc(v)).unwrap();
        }
    }
    out
}

fn child<'a, 'i>(node: Node<'a, 'i>, tag: &str) -> Result<Node<'a, 'i>, String> {
    node.children()
        .find(|n| n.has_tag_name(tag))
        .ok_or(format!("no {tag} element"))
}

/// Every element child of `node`, serialized with its attributes (no text content; used for the
/// unit definitions, whose FMI 3.0 form is the FMI 2.0 one).
fn copy_tree(node: Node, indent: usize, out: &mut String) {
    let pad = " ".repeat(indent);
    let attrs: String = node
        .attributes()
        .map(|a| format!(" {}=\"{}\"", a.name(), esc(a.value())))
        .collect();
    let kids: Vec<Node> = node.children().filter(Node::is_element).collect();
    let tag = node.tag_name().name();
    if kids.is_empty() {
        writeln!(out, "{pad}<{tag}{attrs}/>").unwrap();
    } else {
        writeln!(out, "{pad}<{tag}{attrs}>").unwrap();
        for k in kids {
            copy_tree(k, indent + 2, out);
        }
        writeln!(out, "{pad}</{tag}>").unwrap();
    }
}

/// Value references of the 1-based variable indices in `list` (a space-separated attribute).
fn vrs_of(list: &str, vrs: &[String]) -> Result<String, String> {
    list.split_whitespace()
        .map(|i| {
            i.parse::<usize>()
                .ok()
                .and_then(|i| vrs.get(i.wrapping_sub(1)))
                .cloned()
                .ok_or(format!("bad variable index {i}"))
        })
        .collect::<Result<Vec<_>, _>>()
        .map(|v| v.join(" "))
}

/// The FMI 3.0 model description of the FMI 2.0 one in `text`.
pub fn generate(text: &str) -> Result<String, String> {
    let doc = roxmltree::Document::parse(text).map_err(|e| e.to_string())?;
    let root = doc.root_element();
    let mut out = String::new();
    out.push_str("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    out.push_str(
        "<!-- Generated by fmu/build.rs (build_fmi3.rs) from modelDescription.xml, the FMI 2.0 model\n     description and single source of truth of the variables: do not edit. -->\n",
    );
    let head = copy_attrs(
        root,
        &[
            ("modelName", "modelName"),
            ("guid", "instantiationToken"),
            ("description", "description"),
            ("author", "author"),
            ("version", "version"),
            ("license", "license"),
            ("generationTool", "generationTool"),
            ("variableNamingConvention", "variableNamingConvention"),
        ],
    );
    writeln!(out, "<fmiModelDescription\n  fmiVersion=\"3.0\"{head}>").unwrap();

    let me = child(root, "ModelExchange")?;
    let cs = child(root, "CoSimulation")?;
    let common = [
        ("modelIdentifier", "modelIdentifier"),
        ("needsExecutionTool", "needsExecutionTool"),
        (
            "canBeInstantiatedOnlyOncePerProcess",
            "canBeInstantiatedOnlyOncePerProcess",
        ),
        ("canGetAndSetFMUstate", "canGetAndSetFMUState"),
        ("canSerializeFMUstate", "canSerializeFMUState"),
        (
            "providesDirectionalDerivative",
            "providesDirectionalDerivatives",
        ),
    ];
    let never = " providesAdjointDerivatives=\"false\" providesPerElementDependencies=\"false\" providesEvaluateDiscreteStates=\"false\"";
    let needs_step = me.attribute("completedIntegratorStepNotNeeded") != Some("true");
    writeln!(
        out,
        "\n  <ModelExchange{}{never} needsCompletedIntegratorStep=\"{needs_step}\"/>",
        copy_attrs(me, &common)
    )
    .unwrap();
    writeln!(
        out,
        "\n  <CoSimulation{}{}{never} providesIntermediateUpdate=\"false\" mightReturnEarlyFromDoStep=\"true\" canReturnEarlyAfterIntermediateUpdate=\"false\" hasEventMode=\"true\"/>",
        copy_attrs(cs, &common),
        copy_attrs(
            cs,
            &[
                (
                    "canHandleVariableCommunicationStepSize",
                    "canHandleVariableCommunicationStepSize"
                ),
                ("maxOutputDerivativeOrder", "maxOutputDerivativeOrder"),
            ]
        )
    )
    .unwrap();

    if let Ok(units) = child(root, "UnitDefinitions") {
        out.push('\n');
        copy_tree(units, 2, &mut out);
    }

    if let Ok(types) = child(root, "TypeDefinitions") {
        out.push_str("\n  <TypeDefinitions>\n");
        for t in types.children().filter(|n| n.has_tag_name("SimpleType")) {
            let e = child(t, "Enumeration").map_err(|_| {
                format!(
                    "type {}: only Enumeration types are translated",
                    t.attribute("name").unwrap_or_default()
                )
            })?;
            let type_name = t.attribute("name").unwrap_or_default();
            writeln!(
                out,
                "    <EnumerationType{}{}>",
                copy_attrs(t, &[("name", "name")]),
                description3(t, type_name)?
            )
            .unwrap();
            for item in e.children().filter(|n| n.has_tag_name("Item")) {
                let key = format!("{type_name}.{}", item.attribute("name").unwrap_or_default());
                writeln!(
                    out,
                    "      <Item{}{}/>",
                    copy_attrs(item, &[("name", "name"), ("value", "value")]),
                    description3(item, &key)?
                )
                .unwrap();
            }
            out.push_str("    </EnumerationType>\n");
        }
        out.push_str("  </TypeDefinitions>\n");
    }

    if let Ok(cats) = child(root, "LogCategories") {
        out.push('\n');
        copy_tree(cats, 2, &mut out);
    }
    if let Ok(exp) = child(root, "DefaultExperiment") {
        out.push('\n');
        copy_tree(exp, 2, &mut out);
    }

    let vars: Vec<Node> = child(root, "ModelVariables")?
        .children()
        .filter(|n| n.has_tag_name("ScalarVariable"))
        .collect();
    let vrs: Vec<String> = vars
        .iter()
        .map(|v| {
            v.attribute("valueReference")
                .unwrap_or_default()
                .to_string()
        })
        .collect();
    out.push_str("\n  <ModelVariables>\n");
    for v in &vars {
        let ty = v
            .children()
            .find(|n| n.is_element())
            .ok_or("variable without type")?;
        let tag = match ty.tag_name().name() {
            "Real" => "Float64",
            "Integer" => "Int32",
            "Boolean" => "Boolean",
            "Enumeration" => "Enumeration",
            other => return Err(format!("type {other} is not translated")),
        };
        let mut attrs = copy_attrs(
            *v,
            &[("name", "name"), ("valueReference", "valueReference")],
        );
        attrs += &description3(*v, v.attribute("name").unwrap_or_default())?;
        attrs += &copy_attrs(
            *v,
            &[
                ("causality", "causality"),
                ("variability", "variability"),
                ("initial", "initial"),
            ],
        );
        attrs += &copy_attrs(
            ty,
            &[
                ("declaredType", "declaredType"),
                ("unit", "unit"),
                ("start", "start"),
                ("min", "min"),
                ("max", "max"),
            ],
        );
        if let Some(d) = ty.attribute("derivative") {
            write!(attrs, " derivative=\"{}\"", vrs_of(d, &vrs)?).unwrap();
        }
        writeln!(out, "    <{tag}{attrs}/>").unwrap();
    }
    out.push_str("  </ModelVariables>\n");

    let structure = child(root, "ModelStructure")?;
    out.push_str("\n  <ModelStructure>\n");
    for (section, tag) in [
        ("Outputs", "Output"),
        ("Derivatives", "ContinuousStateDerivative"),
        ("InitialUnknowns", "InitialUnknown"),
    ] {
        let Ok(s) = child(structure, section) else {
            continue;
        };
        for u in s.children().filter(|n| n.has_tag_name("Unknown")) {
            let index = u.attribute("index").ok_or("Unknown without index")?;
            let mut line = format!("    <{tag} valueReference=\"{}\"", vrs_of(index, &vrs)?);
            if let Some(d) = u.attribute("dependencies") {
                write!(line, " dependencies=\"{}\"", vrs_of(d, &vrs)?).unwrap();
            }
            writeln!(out, "{line}/>").unwrap();
        }
    }
    for name in crate::event_indicators(root)? {
        let i = vars
            .iter()
            .position(|v| v.attribute("name") == Some(&name))
            .ok_or(format!("event indicator {name} is not a variable"))?;
        writeln!(out, "    <EventIndicator valueReference=\"{}\"/>", vrs[i]).unwrap();
    }
    out.push_str("  </ModelStructure>\n</fmiModelDescription>\n");
    Ok(out)
}
