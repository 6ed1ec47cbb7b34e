//! Where in a URDF's text a parse error is (issue #22 item 17): the XML
//! deserializer says "custom: invalid float literal" or "missing field `ixy`"
//! without a position; this scan of the text finds the element it is about
//! and gives its line, column and the element as written.

/// Attributes read as numbers (one or a list): a value that does not parse is the first
/// suspect of a number error.
const NUMERIC: [&str; 22] = [
    "xyz",
    "rpy",
    "value",
    "ixx",
    "ixy",
    "ixz",
    "iyy",
    "iyz",
    "izz",
    "lower",
    "upper",
    "effort",
    "velocity",
    "damping",
    "friction",
    "radius",
    "length",
    "size",
    "scale",
    "multiplier",
    "offset",
    "soft_lower_limit",
];

/// Elements whose `value` attribute is a number (`<mass value>`; not e.g. `<param value>`).
fn numeric_attribute(element: &str, attribute: &str) -> bool {
    match attribute {
        "value" => element == "mass",
        a => NUMERIC.contains(&a),
    }
}

/// The elements that must carry the field `field` (as an attribute or a child element).
fn holders(field: &str) -> &'static [&'static str] {
    match field {
        "ixx" | "ixy" | "ixz" | "iyy" | "iyz" | "izz" => &["inertia"],
        "value" => &["mass"],
        "mass" | "inertia" => &["inertial"],
        "name" => &["robot", "link", "joint"],
        "type" => &["joint"],
        "parent" | "child" => &["joint"],
        "link" => &["parent", "child"],
        "filename" => &["mesh"],
        "radius" => &["cylinder", "sphere", "capsule"],
        "length" => &["cylinder", "capsule"],
        "size" => &["box"],
        "geometry" => &["visual", "collision"],
        "effort" | "velocity" => &["limit"],
        _ => &[],
    }
}

/// One start tag: where, its name, its attributes and (once closed) its child elements.
struct Tag<'t> {
    line: usize,
    column: usize,
    name: &'t str,
    attributes: Vec<(&'t str, &'t str)>,
    children: Vec<&'t str>,
}

impl Tag<'_> {
    fn describe(&self, attribute: Option<&str>) -> String {
        let shown = match attribute.and_then(|a| self.attributes.iter().find(|(k, _)| *k == a)) {
            Some((k, v)) => format!("<{} {k}=\"{v}\">", self.name),
            None => format!("<{}>", self.name),
        };
        format!("line {}, column {}: {shown}", self.line, self.column)
    }
}

/// The attributes of a start tag's inside (`name a="1" b='2'`).
fn attributes(inside: &str) -> Vec<(&str, &str)> {
    let mut out = Vec::new();
    let mut rest = inside;
    while let Some(eq) = rest.find('=') {
        let key = rest[..eq].trim();
        let after = rest[eq + 1..].trim_start();
        let Some(quote) = after.chars().next().filter(|c| *c == '"' || *c == '\'') else {
            break;
        };
        let Some(end) = after[1..].find(quote) else {
            break;
        };
        out.push((key, &after[1..1 + end]));
        rest = &after[end + 2..];
    }
    out
}

/// Line and column of byte offsets met in increasing order, the lines counted from the last
/// offset on (linear in the text's length).
struct Lines {
    counted: usize,
    line: usize,
    line_start: usize,
}

impl Default for Lines {
    fn default() -> Self {
        Self {
            counted: 0,
            line: 1,
            line_start: 0,
        }
    }
}

impl Lines {
    /// `(line, column)` of byte `at` of `text` (1-based), `at` not before the last one.
    fn at(&mut self, text: &str, at: usize) -> (usize, usize) {
        let between = &text[self.counted..at];
        self.line += between.matches('\n').count();
        if let Some(n) = between.rfind('\n') {
            self.line_start = self.counted + n + 1;
        }
        self.counted = at;
        (self.line, at - self.line_start + 1)
    }
}

/// The first tag (in document order) for which `judge(tag)` is `Some(attribute)`; tags are
/// judged when they close (their child elements known).
fn find<'t>(text: &'t str, judge: &dyn Fn(&Tag<'t>) -> Option<Option<&'t str>>) -> Option<String> {
    let mut stack: Vec<Tag<'t>> = Vec::new();
    let mut found: Option<(usize, String)> = None;
    let settle = |tag: Tag<'t>, found: &mut Option<(usize, String)>| {
        if let Some(attr) = judge(&tag) {
            let key = tag.line * 1_000_000 + tag.column;
            if found.as_ref().is_none_or(|(k, _)| key < *k) {
                *found = Some((key, tag.describe(attr)));
            }
        }
    };
    let (mut i, mut lines) = (0, Lines::default());
    while let Some(open) = text[i..].find('<').map(|o| i + o) {
        let rest = &text[open..];
        let skip_to = |end: &str| rest.find(end).map_or(text.len(), |e| open + e + end.len());
        if rest.starts_with("<!--") {
            i = skip_to("-->");
        } else if rest.starts_with("<![CDATA[") {
            i = skip_to("]]>");
        } else if rest.starts_with("<?") || rest.starts_with("<!") {
            i = skip_to(">");
        } else if let Some(close) = rest.strip_prefix("</") {
            i = skip_to(">");
            let name = close.split(|c: char| c == '>' || c.is_whitespace()).next();
            if let Some(pos) = stack.iter().rposition(|t| Some(t.name) == name) {
                for tag in stack.drain(pos..) {
                    settle(tag, &mut found);
                }
            }
        } else {
            let end = rest.find('>').unwrap_or(rest.len());
            let inside = &rest[1..end];
            let self_closing = inside.ends_with('/');
            let inside = inside.trim_end_matches('/');
            let name_end = inside.find(char::is_whitespace).unwrap_or(inside.len());
            let (line, column) = lines.at(text, open);
            let tag = Tag {
                line,
                column,
                name: &inside[..name_end],
                attributes: attributes(&inside[name_end..]),
                children: Vec::new(),
            };
            if let Some(parent) = stack.last_mut() {
                parent.children.push(tag.name);
            }
            if self_closing {
                settle(tag, &mut found);
            } else {
                stack.push(tag);
            }
            i = open + end;
        }
    }
    while let Some(tag) = stack.pop() {
        settle(tag, &mut found);
    }
    found.map(|(_, s)| s)
}

/// `message` with where it happened when the text shows it: `missing field `f``: the first
/// element that should hold `f` and does not; a number error: the first numeric attribute
/// whose value is not a list of numbers.
pub(super) fn locate(text: &str, message: &str) -> String {
    let field = message
        .split_once("missing field `")
        .and_then(|(_, r)| r.split_once('`'))
        .map(|(f, _)| f);
    let place = match field {
        Some(f) if !holders(f).is_empty() => find(text, &|t| {
            let has = t.attributes.iter().any(|(k, _)| *k == f) || t.children.contains(&f);
            (holders(f).contains(&t.name) && !has).then_some(None)
        }),
        _ if ["float", "digit", "number"]
            .iter()
            .any(|w| message.contains(w)) =>
        {
            find(text, &|t| {
                t.attributes
                    .iter()
                    .find(|(k, v)| {
                        numeric_attribute(t.name, k)
                            && v.split_whitespace().any(|x| x.parse::<f64>().is_err())
                    })
                    .map(|(k, _)| Some(*k))
            })
        }
        _ => None,
    };
    match place {
        Some(p) => format!("{message} ({p})"),
        None => message.to_string(),
    }
}

/// The first `xyz` or `rpy` attribute that is not three numbers separated by white space,
/// with its line, column and element. The XML deserializer reads such a value without an
/// error in some forms (`xyz="1,5 0 0 0"`: a decimal comma and a fourth number), which
/// would silently move a joint: the text is checked once after it parsed.
pub(super) fn malformed_vector(text: &str) -> Option<String> {
    find(text, &|t| {
        t.attributes
            .iter()
            .find(|(k, v)| {
                (*k == "xyz" || *k == "rpy") && {
                    let parts: Vec<&str> = v.split_whitespace().collect();
                    parts.len() != 3 || parts.iter().any(|x| x.parse::<f64>().is_err())
                }
            })
            .map(|(k, _)| Some(*k))
    })
}

#[cfg(test)]
mod tests {
    use super::{locate, malformed_vector};

    #[test]
    fn number_and_missing_field_errors_get_their_line_and_element() {
        let text = "<robot name=\"r\">\n  <link name=\"a\">\n    <inertial>\n      <mass value=\"1\"/>\n      <inertia ixx=\"1\" iyy=\"1\" izz=\"1\" ixz=\"0\" iyz=\"0\"/>\n    </inertial>\n  </link>\n  <!-- <origin xyz=\"x\"/> -->\n  <joint name=\"j\">\n    <origin xyz=\"0 0 1,5\"/>\n  </joint>\n</robot>\n";
        assert_eq!(
            locate(text, "missing field `ixy`"),
            "missing field `ixy` (line 5, column 7: <inertia>)"
        );
        assert_eq!(
            locate(text, "custom: invalid float literal"),
            "custom: invalid float literal (line 10, column 5: <origin xyz=\"0 0 1,5\">)"
        );
        assert_eq!(
            locate(text, "missing field `type`"),
            "missing field `type` (line 9, column 3: <joint>)"
        );
        assert_eq!(locate(text, "something else"), "something else");
        assert_eq!(
            malformed_vector(text).as_deref(),
            Some("line 10, column 5: <origin xyz=\"0 0 1,5\">")
        );
        let four = "<robot>\n<joint><origin xyz=\"1 0 0 0\" rpy=\"0 0 0\"/><axis xyz=\"0 0 1\"/></joint></robot>";
        assert_eq!(
            malformed_vector(four).as_deref(),
            Some("line 2, column 8: <origin xyz=\"1 0 0 0\">")
        );
        let fine = "<robot><joint><origin xyz=\" 1 0\t0 \" rpy=\"0 0 1e-3\"/></joint></robot>";
        assert_eq!(malformed_vector(fine), None);
        let no_mass = "<robot><link name=\"a\"><inertial>\n<inertia/></inertial></link></robot>";
        assert_eq!(
            locate(no_mass, "missing field `mass`"),
            "missing field `mass` (line 1, column 23: <inertial>)"
        );
    }
}
