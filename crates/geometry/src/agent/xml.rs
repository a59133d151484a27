//! A small XML element reader for SRDF files: elements, attributes (single or double quotes, the
//! five predefined entities), comments, the `<?xml ..?>` declaration and `<!DOCTYPE ..>` skipped,
//! text ignored. Every element and attribute keeps its 1-based line and column for error
//! messages. Depth and size are bounded by the input (no recursion).

/// A position in the text.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Pos {
    /// 1-based line.
    pub line: usize,
    /// 1-based column (in characters).
    pub col: usize,
}

/// One element with its attributes and child elements.
#[derive(Clone, Debug)]
pub struct Element {
    /// Tag name.
    pub name: String,
    /// Attributes in document order: name, value, where the value starts.
    pub attrs: Vec<(String, String, Pos)>,
    /// Child elements.
    pub children: Vec<Element>,
    /// Where the element's `<` is.
    pub at: Pos,
}

impl Element {
    /// The value of attribute `name` and where it is.
    pub fn attr(&self, name: &str) -> Option<(&str, Pos)> {
        self.attrs
            .iter()
            .find(|(n, _, _)| n == name)
            .map(|(_, v, p)| (v.as_str(), *p))
    }
}

/// A syntax error: where and what.
#[derive(Clone, Debug, PartialEq)]
pub struct XmlError {
    pub at: Pos,
    pub message: String,
}

struct Cursor<'a> {
    chars: std::iter::Peekable<std::str::Chars<'a>>,
    pos: Pos,
}

impl Cursor<'_> {
    fn next(&mut self) -> Option<char> {
        let c = self.chars.next()?;
        if c == '\n' {
            self.pos.line += 1;
            self.pos.col = 1;
        } else {
            self.pos.col += 1;
        }
        Some(c)
    }

    fn peek(&mut self) -> Option<char> {
        self.chars.peek().copied()
    }

    fn err<T>(&self, message: impl Into<String>) -> Result<T, XmlError> {
        Err(XmlError {
            at: self.pos,
            message: message.into(),
        })
    }

    fn skip_space(&mut self) {
        while self.peek().is_some_and(char::is_whitespace) {
            self.next();
        }
    }

    /// Skips past `end` (after `<!--`, `<?`, `<!`).
    fn skip_until(&mut self, end: &str) -> Result<(), XmlError> {
        let mut window = String::new();
        while let Some(c) = self.next() {
            window.push(c);
            if window.ends_with(end) {
                return Ok(());
            }
        }
        self.err(format!("unterminated markup: expected `{end}`"))
    }

    fn name(&mut self) -> Result<String, XmlError> {
        let mut s = String::new();
        while let Some(c) = self.peek() {
            if c.is_alphanumeric() || matches!(c, '_' | '-' | ':' | '.') {
                s.push(c);
                self.next();
            } else {
                break;
            }
        }
        if s.is_empty() {
            return self.err("expected a name");
        }
        Ok(s)
    }

    fn value(&mut self) -> Result<(String, Pos), XmlError> {
        let quote = match self.next() {
            Some(q @ ('"' | '\'')) => q,
            _ => return self.err("expected a quoted attribute value"),
        };
        let at = self.pos;
        let mut raw = String::new();
        loop {
            match self.next() {
                Some(c) if c == quote => break,
                Some('<') => return self.err("`<` inside an attribute value"),
                Some(c) => raw.push(c),
                None => return self.err("unterminated attribute value"),
            }
        }
        let v = raw
            .replace("&lt;", "<")
            .replace("&gt;", ">")
            .replace("&quot;", "\"")
            .replace("&apos;", "'")
            .replace("&amp;", "&");
        Ok((v, at))
    }
}

/// Reads the document's root element.
pub fn parse(text: &str) -> Result<Element, XmlError> {
    let mut c = Cursor {
        chars: text.chars().peekable(),
        pos: Pos { line: 1, col: 1 },
    };
    // Open elements; the finished root ends up in `root`.
    let mut stack: Vec<Element> = Vec::new();
    let mut root: Option<Element> = None;
    while let Some(ch) = c.peek() {
        if ch != '<' {
            if stack.is_empty() && !ch.is_whitespace() {
                return c.err("text outside the root element");
            }
            c.next();
            continue;
        }
        let at = c.pos;
        c.next();
        match c.peek() {
            Some('?') => c.skip_until("?>")?,
            Some('!') => {
                c.next();
                if c.peek() == Some('-') {
                    c.skip_until("-->")?;
                } else {
                    c.skip_until(">")?;
                }
            }
            Some('/') => {
                c.next();
                let name = c.name()?;
                c.skip_space();
                if c.next() != Some('>') {
                    return c.err("expected `>`");
                }
                let Some(done) = stack.pop() else {
                    return c.err(format!("`</{name}>` closes nothing"));
                };
                if done.name != name {
                    return c.err(format!(
                        "`</{name}>` closes `<{}>` opened at {}:{}",
                        done.name, done.at.line, done.at.col
                    ));
                }
                finish(done, &mut stack, &mut root, &c)?;
            }
            _ => {
                let (e, closed) = open_tag(&mut c, at)?;
                if closed {
                    finish(e, &mut stack, &mut root, &c)?;
                } else {
                    stack.push(e);
                }
            }
        }
    }
    if let Some(open) = stack.last() {
        return Err(XmlError {
            at: open.at,
            message: format!("`<{}>` is never closed", open.name),
        });
    }
    root.ok_or(XmlError {
        at: c.pos,
        message: "no root element".into(),
    })
}

/// Reads `name attr="v" ... >` or `... />` after the `<`; whether it closed itself.
fn open_tag(c: &mut Cursor, at: Pos) -> Result<(Element, bool), XmlError> {
    let name = c.name()?;
    let mut e = Element {
        name,
        attrs: Vec::new(),
        children: Vec::new(),
        at,
    };
    loop {
        c.skip_space();
        match c.peek() {
            Some('>') => {
                c.next();
                return Ok((e, false));
            }
            Some('/') => {
                c.next();
                if c.next() != Some('>') {
                    return c.err("expected `>` after `/`");
                }
                return Ok((e, true));
            }
            None => return c.err(format!("unterminated tag `<{}`", e.name)),
            _ => {
                let key = c.name()?;
                c.skip_space();
                if c.next() != Some('=') {
                    return c.err(format!("expected `=` after attribute `{key}`"));
                }
                c.skip_space();
                let (v, p) = c.value()?;
                if e.attr(&key).is_some() {
                    return c.err(format!("attribute `{key}` given twice"));
                }
                e.attrs.push((key, v, p));
            }
        }
    }
}

fn finish(
    e: Element,
    stack: &mut [Element],
    root: &mut Option<Element>,
    c: &Cursor,
) -> Result<(), XmlError> {
    match stack.last_mut() {
        Some(parent) => parent.children.push(e),
        None if root.is_none() => *root = Some(e),
        None => return c.err("a second root element"),
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn elements_attributes_and_positions() {
        let doc = "<?xml version=\"1.0\"?>\n<!-- c -->\n<robot name='r'>\n  <group name=\"a&amp;b\">\n    <joint name=\"j\"/>\n  </group>\n</robot>\n";
        let r = parse(doc).unwrap();
        assert_eq!(r.name, "robot");
        assert_eq!(r.attr("name").unwrap().0, "r");
        let g = &r.children[0];
        assert_eq!(g.attr("name").unwrap().0, "a&b");
        assert_eq!(g.at, Pos { line: 4, col: 3 });
        assert_eq!(
            g.children[0].attr("name").unwrap().1,
            Pos { line: 5, col: 18 }
        );
    }

    #[test]
    fn errors_say_where() {
        let e = parse("<robot>\n  <group>\n</robot>").unwrap_err();
        assert_eq!(e.at.line, 3);
        assert!(e.message.contains("opened at 2:3"), "{}", e.message);
        assert!(parse("<robot name=x/>").is_err());
        assert!(parse("<a/><b/>").is_err());
        assert!(parse("<a").is_err());
        assert!(parse("").is_err());
    }
}
