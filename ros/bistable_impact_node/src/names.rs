//! ROS 2 names as rcl resolves them (<https://design.ros2.org/articles/topic_and_service_names.html>,
//! `rcl_expand_topic_name`, `rcl_remap`): validation of node names, namespaces and topic or
//! service names; expansion of relative (`bistable/impacts`), private (`~/x`) and absolute
//! (`/clock`) names with `{node}` and `{ns}`/`{namespace}` substitution; and remapping rules
//! `[node:]from:=to`, `[node:]__node:=name`, `[node:]__ns:=/namespace` (`rostopic://` and
//! `rosservice://` prefixes restrict a rule to topics or services). The first matching rule
//! wins, as in rcl; a topic rule's `from` and `to` are expanded with the node's (remapped)
//! name and namespace and `from` is compared with the expanded name.

/// Longest fully qualified topic or service name (rmw's `RMW_TOPIC_MAX_NAME_LENGTH`: 255
/// bytes of a DDS name less the `rt/` prefix and the service suffixes).
pub const MAX_NAME_LENGTH: usize = 247;
/// Longest node name (rmw's `RMW_NODE_NAME_MAX_NAME_LENGTH`).
pub const MAX_NODE_NAME_LENGTH: usize = 255;

/// What a topic/service remapping rule applies to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// Topics (publishers, subscriptions).
    Topic,
    /// Services.
    Service,
}

/// One `-r` rule.
#[derive(Debug, Clone, PartialEq, Eq)]
enum Rule {
    /// `__node:=name` (also `__name:=`).
    Node(String),
    /// `__ns:=/namespace`.
    Namespace(String),
    /// `from:=to`, for topics and services unless restricted to one kind.
    Name {
        kinds: Option<Kind>,
        from: String,
        to: String,
    },
}

/// A parsed `-r` remapping rule, valid by rcl's rules.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Remap {
    /// Applies only to the node of this name (`node:` prefix), else to every node.
    node: Option<String>,
    rule: Rule,
}

impl Remap {
    /// Parses and validates one rule (the argument after `-r`/`--remap`).
    pub fn parse(arg: &str) -> Result<Self, String> {
        let bad = |why: String| format!("invalid remapping rule '{arg}': {why}");
        let (lhs, to) = arg
            .split_once(":=")
            .ok_or_else(|| bad("expected [node:]from:=to".to_owned()))?;
        // The `rostopic://` and `rosservice://` schemes contain a ':' of their own.
        let scheme = |s: &str| s.starts_with("rostopic://") || s.starts_with("rosservice://");
        let (node, lhs) = match lhs.split_once(':') {
            Some((node, rest)) if !scheme(lhs) => {
                validate_node_name(node).map_err(|e| bad(format!("node prefix: {e}")))?;
                (Some(node.to_owned()), rest)
            }
            _ => (None, lhs),
        };
        let rule = match lhs {
            "__node" | "__name" => {
                validate_node_name(to).map_err(|e| bad(format!("node name: {e}")))?;
                Rule::Node(to.to_owned())
            }
            "__ns" => {
                validate_namespace(to).map_err(|e| bad(format!("namespace: {e}")))?;
                Rule::Namespace(to.to_owned())
            }
            _ if lhs.starts_with("__") => {
                return Err(bad(format!(
                    "unknown special name '{lhs}' (only __node, __name and __ns)"
                )))
            }
            _ => {
                let (kinds, from) = if let Some(f) = lhs.strip_prefix("rostopic://") {
                    (Some(Kind::Topic), f)
                } else if let Some(f) = lhs.strip_prefix("rosservice://") {
                    (Some(Kind::Service), f)
                } else {
                    (None, lhs)
                };
                if from.contains('*') {
                    return Err(bad("wildcards (* and **) are not supported".to_owned()));
                }
                validate_name(from).map_err(|e| bad(format!("'{from}': {e}")))?;
                validate_name(to).map_err(|e| bad(format!("'{to}': {e}")))?;
                Rule::Name {
                    kinds,
                    from: from.to_owned(),
                    to: to.to_owned(),
                }
            }
        };
        Ok(Self { node, rule })
    }

    fn applies_to(&self, node: &str) -> bool {
        self.node.as_deref().is_none_or(|n| n == node)
    }
}

/// A node's name, namespace and remapping rules: resolves the names it uses.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Names {
    node: String,
    namespace: String,
    rules: Vec<Remap>,
}

impl Names {
    /// The node `node` (its name in the code) in `namespace` with `rules` applied: the first
    /// `__node` and the first `__ns` rule that apply to `node` rename it (node prefixes match
    /// the name in the code, as in rcl).
    pub fn new(node: &str, namespace: &str, rules: Vec<Remap>) -> Result<Self, String> {
        validate_node_name(node)?;
        validate_namespace(namespace)?;
        let applying = || rules.iter().filter(|r| r.applies_to(node));
        let name = applying()
            .find_map(|r| match &r.rule {
                Rule::Node(n) => Some(n.as_str()),
                _ => None,
            })
            .unwrap_or(node)
            .to_owned();
        let namespace = applying()
            .find_map(|r| match &r.rule {
                Rule::Namespace(ns) => Some(ns.as_str()),
                _ => None,
            })
            .unwrap_or(namespace)
            .to_owned();
        Ok(Self {
            node: name,
            namespace,
            rules,
        })
    }

    /// The node's (remapped) name.
    pub fn node(&self) -> &str {
        &self.node
    }

    /// The node's (remapped) namespace, `/` or `/a/b`.
    pub fn namespace(&self) -> &str {
        &self.namespace
    }

    /// The fully qualified node name, e.g. `/rig1/bistable_impact`.
    pub fn fully_qualified(&self) -> String {
        join(&self.namespace, &self.node)
    }

    /// The fully qualified name of the topic or service `name` as the node uses it: expanded
    /// against the node's name and namespace, then remapped by the first topic/service rule
    /// of this node whose expanded `from` equals it.
    pub fn resolve(&self, name: &str, kind: Kind) -> Result<String, String> {
        let expanded = expand(name, &self.node, &self.namespace)?;
        for r in self.rules.iter().filter(|r| r.applies_to(&self.node)) {
            if let Rule::Name { kinds, from, to } = &r.rule {
                if kinds.is_none_or(|k| k == kind)
                    && expand(from, &self.node, &self.namespace)? == expanded
                {
                    return expand(to, &self.node, &self.namespace);
                }
            }
        }
        Ok(expanded)
    }
}

fn join(namespace: &str, name: &str) -> String {
    if namespace == "/" {
        format!("/{name}")
    } else {
        format!("{namespace}/{name}")
    }
}

/// Checks a node name: not empty, only letters, digits and `_`, not starting with a digit,
/// at most [`MAX_NODE_NAME_LENGTH`] bytes (rmw's rules); no `__`, which the DDS mapping of
/// ros2-client refuses.
pub fn validate_node_name(name: &str) -> Result<(), String> {
    if name.is_empty() {
        return Err("a node name must not be empty".to_owned());
    }
    if let Some(c) = name
        .chars()
        .find(|c| !(c.is_ascii_alphanumeric() || *c == '_'))
    {
        return Err(format!(
            "node name '{name}' contains '{c}' (only letters, digits and _)"
        ));
    }
    if name.starts_with(|c: char| c.is_ascii_digit()) {
        return Err(format!("node name '{name}' must not start with a digit"));
    }
    if name.contains("__") {
        return Err(format!("node name '{name}' must not contain '__'"));
    }
    if name.len() > MAX_NODE_NAME_LENGTH {
        return Err(format!(
            "node name is longer than {MAX_NODE_NAME_LENGTH} characters"
        ));
    }
    Ok(())
}

/// Checks a node namespace: `/`, or absolute tokens as in a fully qualified topic name.
pub fn validate_namespace(ns: &str) -> Result<(), String> {
    if ns == "/" {
        return Ok(());
    }
    if !ns.starts_with('/') {
        return Err(format!(
            "namespace '{ns}' must be absolute (start with '/'), as rcl requires for __ns"
        ));
    }
    validate_full(ns).map_err(|e| format!("namespace {e}"))
}

/// Checks a topic or service name before expansion (`rcl_validate_topic_name`): not empty;
/// letters, digits, `_`, `/`, balanced `{...}` substitutions (letters, digits, `_` inside) and a
/// leading `~` (followed by `/` if anything follows); not starting with a digit, no token
/// starting with a digit, no `//`, no trailing `/`, no `__`.
pub fn validate_name(name: &str) -> Result<(), String> {
    if name.is_empty() {
        return Err("a topic or service name must not be empty".to_owned());
    }
    if name.starts_with(|c: char| c.is_ascii_digit()) {
        return Err(format!("'{name}' must not start with a digit"));
    }
    if name.len() > 1 && name.ends_with('/') {
        return Err(format!("'{name}' must not end with '/'"));
    }
    if name.starts_with('~') && name.len() > 1 && !name[1..].starts_with('/') {
        return Err(format!("in '{name}', '~' must be followed by '/'"));
    }
    let mut in_braces = false;
    for (i, c) in name.char_indices() {
        match c {
            '~' if i > 0 => return Err(format!("'{name}': '~' is only allowed first")),
            '{' if in_braces => return Err(format!("'{name}': nested '{{'")),
            '{' => in_braces = true,
            '}' if !in_braces => return Err(format!("'{name}': unbalanced '}}'")),
            '}' => in_braces = false,
            '/' if in_braces => return Err(format!("'{name}': '/' inside a substitution")),
            '~' | '/' | '_' => {}
            c if c.is_ascii_alphanumeric() => {}
            c => {
                return Err(format!(
                    "'{name}' contains '{c}' (only letters, digits, _, /, a leading ~ and {{...}})"
                ))
            }
        }
    }
    if in_braces {
        return Err(format!("'{name}': unbalanced '{{'"));
    }
    let mut rest = name;
    while let Some((_, after)) = rest.split_once('{') {
        let (key, tail) = after.split_once('}').unwrap_or((after, ""));
        if !matches!(key, "node" | "ns" | "namespace") {
            return Err(format!(
                "'{name}': unknown substitution '{{{key}}}' (only {{node}}, {{ns}}, {{namespace}})"
            ));
        }
        rest = tail;
    }
    check_tokens(name)
}

/// Rules shared by every form: no `//`, no token starting with a digit, no `__`.
fn check_tokens(name: &str) -> Result<(), String> {
    if name.contains("//") {
        return Err(format!("'{name}' contains '//'"));
    }
    if name
        .split('/')
        .any(|t| t.starts_with(|c: char| c.is_ascii_digit()))
    {
        return Err(format!("in '{name}', a token starts with a digit"));
    }
    if name.contains("__") {
        return Err(format!(
            "'{name}' contains '__' (not allowed in ROS 2 names)"
        ));
    }
    Ok(())
}

/// Checks a fully qualified name (`rmw_validate_full_topic_name`): absolute, letters, digits,
/// `_` and `/` only, plus the token rules, at most [`MAX_NAME_LENGTH`] bytes.
fn validate_full(name: &str) -> Result<(), String> {
    if !name.starts_with('/') {
        return Err(format!("'{name}' is not absolute"));
    }
    if name.ends_with('/') {
        return Err(format!("'{name}' must not end with '/'"));
    }
    if let Some(c) = name
        .chars()
        .find(|c| !(c.is_ascii_alphanumeric() || *c == '_' || *c == '/'))
    {
        return Err(format!("'{name}' contains '{c}'"));
    }
    if name.len() > MAX_NAME_LENGTH {
        return Err(format!(
            "'{name}' is longer than {MAX_NAME_LENGTH} characters"
        ));
    }
    check_tokens(name)
}

/// Expands `name` for the node `node` in `namespace` (`rcl_expand_topic_name`): `~` is the
/// node's fully qualified name, `{node}` its name, `{ns}` and `{namespace}` its namespace (the
/// root namespace `/` followed by `/` adds nothing, so `{ns}/x` is `/x` there); a relative
/// result is prefixed with the namespace. The result is validated.
pub fn expand(name: &str, node: &str, namespace: &str) -> Result<String, String> {
    validate_name(name)?;
    let (mut out, mut rest) = match name.strip_prefix('~') {
        Some(rest) => (join(namespace, node), rest),
        None => (String::new(), name),
    };
    // validate_name checked that every '{' is closed and names a known substitution.
    while let Some((before, after)) = rest.split_once('{') {
        out.push_str(before);
        let (key, tail) = after.split_once('}').unwrap_or((after, ""));
        match key {
            "node" => out.push_str(node),
            _ if namespace == "/" && tail.starts_with('/') => {}
            _ => out.push_str(namespace),
        }
        rest = tail;
    }
    out.push_str(rest);
    let full = if out.starts_with('/') {
        out
    } else {
        join(namespace, &out)
    };
    validate_full(&full).map_err(|e| format!("'{name}' expands to {e}"))?;
    Ok(full)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names(rules: &[&str]) -> Result<Names, String> {
        let rules = rules
            .iter()
            .map(|r| Remap::parse(r))
            .collect::<Result<_, _>>()?;
        Names::new("bistable_impact", "/", rules)
    }

    fn topic(n: &Names, name: &str) -> String {
        n.resolve(name, Kind::Topic).unwrap()
    }

    #[test]
    fn expansion_as_rcl_does_it() {
        for (name, node, ns, want) in [
            ("bistable/impacts", "n", "/", "/bistable/impacts"),
            ("bistable/impacts", "n", "/rig1", "/rig1/bistable/impacts"),
            ("bistable/impacts", "n", "/a/b", "/a/b/bistable/impacts"),
            ("/clock", "n", "/rig1", "/clock"),
            ("~", "n", "/rig1", "/rig1/n"),
            ("~/state", "n", "/", "/n/state"),
            ("~/state", "n", "/rig1", "/rig1/n/state"),
            ("{node}/x", "n", "/rig1", "/rig1/n/x"),
            ("/{node}_out", "n", "/rig1", "/n_out"),
            ("{ns}/x", "n", "/rig1", "/rig1/x"),
            ("{namespace}/x", "n", "/a/b", "/a/b/x"),
            ("{ns}/x", "n", "/", "/x"),
            ("~/{node}", "n", "/rig1", "/rig1/n/n"),
        ] {
            assert_eq!(expand(name, node, ns).as_deref(), Ok(want), "{name} {ns}");
        }
        for (name, needle) in [
            ("", "empty"),
            ("1abc", "digit"),
            ("a/1b", "digit"),
            ("a//b", "//"),
            ("a/", "end with"),
            ("a~", "only allowed first"),
            ("~x", "followed by '/'"),
            ("a b", "contains ' '"),
            ("a-b", "contains '-'"),
            ("a__b", "__"),
            ("{nod}/x", "unknown substitution"),
            ("{node", "unbalanced"),
            ("node}", "unbalanced"),
            ("{a{b}}", "nested"),
            ("{ns}", "expands to '/' "),
        ] {
            let err = expand(name, "n", "/").unwrap_err();
            assert!(err.contains(needle), "{name}: {err}");
        }
        let long = "a".repeat(MAX_NAME_LENGTH);
        assert!(expand(&long, "n", "/").unwrap_err().contains("longer"));
        assert!(expand(&long[1..], "n", "/").is_ok());
    }

    #[test]
    fn node_name_and_namespace_rules() {
        let n = names(&[]).unwrap();
        assert_eq!(
            (n.node(), n.namespace(), n.fully_qualified().as_str()),
            ("bistable_impact", "/", "/bistable_impact")
        );
        assert_eq!(topic(&n, "bistable/mass_state"), "/bistable/mass_state");
        let n = names(&["__ns:=/rig1", "__node:=shaker1"]).unwrap();
        assert_eq!(n.fully_qualified(), "/rig1/shaker1");
        assert_eq!(topic(&n, "bistable/impacts"), "/rig1/bistable/impacts");
        assert_eq!(topic(&n, "/clock"), "/clock");
        assert_eq!(topic(&n, "~/x"), "/rig1/shaker1/x");
        // The first matching rule wins; node prefixes match the name in the code.
        let n = names(&[
            "other:__node:=no",
            "bistable_impact:__node:=first",
            "__node:=second",
            "__name:=third",
            "__ns:=/a/b",
            "__ns:=/c",
        ])
        .unwrap();
        assert_eq!(n.fully_qualified(), "/a/b/first");
    }

    #[test]
    fn topic_remapping_as_rcl_does_it() {
        let n = names(&[
            "bistable/impacts:=hits",
            "/clock:=/sim/clock",
            "other:bistable/mass_state:=no",
            "rosservice://bistable/shaker_command:=no",
        ])
        .unwrap();
        assert_eq!(topic(&n, "bistable/impacts"), "/hits");
        assert_eq!(topic(&n, "/clock"), "/sim/clock");
        assert_eq!(topic(&n, "bistable/mass_state"), "/bistable/mass_state");
        assert_eq!(
            topic(&n, "bistable/shaker_command"),
            "/bistable/shaker_command"
        );
        assert_eq!(
            n.resolve("bistable/shaker_command", Kind::Service).unwrap(),
            "/no"
        );
        // In a namespace: `from` and `to` are expanded there; absolute `from` must match the
        // expanded name; `~` and node-specific rules (remapped node name).
        let n = names(&[
            "__ns:=/rig1",
            "__node:=sim",
            "/bistable/impacts:=/never",
            "/rig1/bistable/impacts:=~/impacts",
            "sim:bistable/mass_state:=/abs/state",
            "bistable_impact:bistable/shaker_command:=no",
            "/clock:=clock",
            "rostopic://{node}/x:={ns}/y",
        ])
        .unwrap();
        assert_eq!(topic(&n, "bistable/impacts"), "/rig1/sim/impacts");
        assert_eq!(topic(&n, "bistable/mass_state"), "/abs/state");
        assert_eq!(
            topic(&n, "bistable/shaker_command"),
            "/rig1/bistable/shaker_command"
        );
        assert_eq!(topic(&n, "/clock"), "/rig1/clock");
        assert_eq!(topic(&n, "sim/x"), "/rig1/y");
    }

    #[test]
    fn invalid_rules_are_refused_with_reasons() {
        for (rule, needle) in [
            ("impacts", "expected [node:]from:=to"),
            ("a:=", "empty"),
            (":=b", "empty"),
            ("a:=b c", "contains ' '"),
            ("a:=1b", "digit"),
            ("a/*:=b", "wildcards"),
            ("**/a:=b", "wildcards"),
            ("__ns:=rig1", "must be absolute"),
            ("__ns:=/rig1/", "end with"),
            ("__ns:=/1rig", "digit"),
            ("__node:=a/b", "contains '/'"),
            ("__node:=", "must not be empty"),
            ("__node:=9lives", "digit"),
            ("__log_level:=debug", "unknown special name"),
            ("bad-node:a:=b", "node prefix"),
            ("a:=b~", "only allowed first"),
            ("x:=~y", "followed by '/'"),
            ("a:={nope}", "unknown substitution"),
        ] {
            let err = Remap::parse(rule).unwrap_err();
            assert!(err.contains(needle) && err.contains(rule), "{rule}: {err}");
        }
    }
}
