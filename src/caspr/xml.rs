//! Reading CASPR's XML: one parsed document with its file name, and the element and number
//! look-ups the bodies and cables readers share. Every error names the file, the line and
//! the element ([`CasprError::Element`]).

use super::CasprError;
use nalgebra::Vector3;
use roxmltree::{Document, Node, ParsingOptions};

/// Most XML nodes (elements, texts, comments) a model file may have: CASPR's largest
/// models have a few thousand; the bound keeps a hostile file from exhausting memory.
const MAX_XML_NODES: u32 = 1_000_000;

/// Parses `text` (the contents of `file`). CASPR's files start with a `<!DOCTYPE ...>`
/// naming an external DTD, so such a DOCTYPE is allowed; a DOCTYPE with an internal subset
/// (`[...]`, the only place a file can declare its own entities) is refused before parsing,
/// so no entity is ever expanded and the parsed text is never longer than the file.
/// External entities are never loaded (no resolver).
pub(super) fn parse<'a>(text: &'a str, file: &str) -> Result<Document<'a>, CasprError> {
    if has_internal_subset(text) {
        return Err(CasprError::InternalDtd {
            file: file.to_string(),
        });
    }
    let opt = ParsingOptions {
        allow_dtd: true,
        nodes_limit: MAX_XML_NODES,
        ..ParsingOptions::default()
    };
    Document::parse_with_options(text, opt).map_err(|e| CasprError::Xml {
        file: file.to_string(),
        message: e.to_string(),
    })
}

/// Whether the prolog of `text` (before the root element) has a DOCTYPE with an internal
/// subset: an unquoted `[` inside `<!DOCTYPE ...>`. Comments and processing instructions
/// before it are skipped; text that is not well-formed is left to the parser.
fn has_internal_subset(text: &str) -> bool {
    let mut rest = text.trim_start_matches('\u{feff}');
    loop {
        rest = rest.trim_start();
        if let Some(r) = rest.strip_prefix("<?") {
            match r.find("?>") {
                Some(i) => rest = &r[i + 2..],
                None => return false,
            }
        } else if let Some(r) = rest.strip_prefix("<!--") {
            match r.find("-->") {
                Some(i) => rest = &r[i + 3..],
                None => return false,
            }
        } else if let Some(r) = rest.strip_prefix("<!DOCTYPE") {
            let mut quote: Option<char> = None;
            for ch in r.chars() {
                match (quote, ch) {
                    (Some(q), c) if c == q => quote = None,
                    (Some(_), _) => {}
                    (None, '"' | '\'') => quote = Some(ch),
                    (None, '[') => return true,
                    (None, '>') => return false,
                    (None, _) => {}
                }
            }
            return false;
        } else {
            return false;
        }
    }
}

/// A node of one file, for messages that name the file and the line.
#[derive(Clone, Copy)]
pub(super) struct At<'a, 'i> {
    /// The file name.
    pub file: &'a str,
    /// The element.
    pub node: Node<'a, 'i>,
}

impl<'a, 'i> At<'a, 'i> {
    /// The same file, another element.
    pub fn at(&self, node: Node<'a, 'i>) -> At<'a, 'i> {
        At {
            file: self.file,
            node,
        }
    }

    /// The element's line in its file (1-based).
    pub fn line(&self) -> u32 {
        self.node
            .document()
            .text_pos_at(self.node.range().start)
            .row
    }

    /// An error about this element.
    pub fn err(&self, message: impl Into<String>) -> CasprError {
        CasprError::Element {
            file: self.file.to_string(),
            line: self.line(),
            element: self.node.tag_name().name().to_string(),
            message: message.into(),
        }
    }

    /// The element children of this element.
    pub fn elements(&self) -> impl Iterator<Item = Node<'a, 'i>> {
        self.node.children().filter(|n| n.is_element())
    }

    /// The first child element named `tag` (CASPR reads the first one too).
    pub fn child(&self, tag: &str) -> Result<At<'a, 'i>, CasprError> {
        self.elements()
            .find(|n| n.has_tag_name(tag))
            .map(|n| self.at(n))
            .ok_or_else(|| self.err(format!("missing <{tag}>")))
    }

    /// The attribute `name`, which must be present.
    pub fn attr(&self, name: &str) -> Result<&'a str, CasprError> {
        self.node
            .attribute(name)
            .ok_or_else(|| self.err(format!("missing attribute `{name}`")))
    }

    /// The element's whole text: all its text children joined (comments and processing
    /// instructions between them are not text, as in XML's text content), so
    /// `<mass>2<!-- x -->5.0</mass>` reads `25.0`, not `2`. An element child inside a value
    /// is an error naming this element.
    pub fn text(&self) -> Result<String, CasprError> {
        let mut s = String::new();
        for n in self.node.children() {
            if n.is_element() {
                return Err(self.err(format!(
                    "a value may not contain elements (found <{}>)",
                    n.tag_name().name()
                )));
            }
            if let Some(t) = n.text().filter(|_| n.is_text()) {
                s.push_str(t);
            }
        }
        Ok(s)
    }

    /// The text of child `tag` as one finite number.
    pub fn number(&self, tag: &str) -> Result<f64, CasprError> {
        let c = self.child(tag)?;
        let v = c.numbers(&c.text()?, 1)?;
        Ok(v[0])
    }

    /// The text of child `tag` as three finite numbers separated by white space.
    pub fn vec3(&self, tag: &str) -> Result<Vector3<f64>, CasprError> {
        let c = self.child(tag)?;
        let v = c.numbers(&c.text()?, 3)?;
        Ok(Vector3::new(v[0], v[1], v[2]))
    }

    /// Exactly `n` finite numbers separated by white space, read from `s` (this element's
    /// text or one of its attributes).
    pub fn numbers(&self, s: &str, n: usize) -> Result<Vec<f64>, CasprError> {
        let words: Vec<&str> = s.split_whitespace().collect();
        if words.len() != n {
            return Err(self.err(format!(
                "expected {n} number{}, got `{}`",
                if n == 1 { "" } else { "s" },
                short(s)
            )));
        }
        words
            .iter()
            .map(|w| match w.parse::<f64>() {
                Ok(x) if x.is_finite() => Ok(x),
                Ok(_) => Err(self.err(format!("`{w}` is not a finite number"))),
                Err(_) => Err(self.err(format!("`{}` is not a number", short(w)))),
            })
            .collect()
    }
}

/// At most 40 characters of `s` on one line, for messages.
fn short(s: &str) -> String {
    let one_line: String = s.split_whitespace().collect::<Vec<_>>().join(" ");
    if one_line.chars().count() > 40 {
        format!("{}…", one_line.chars().take(40).collect::<String>())
    } else {
        one_line
    }
}
