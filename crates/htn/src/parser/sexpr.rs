//! Lexer and s-expression reader: HDDL text to a tree of atoms and lists with positions.
//!
//! Atoms are lower-cased (HDDL names are case-insensitive: later stages match on the folded
//! text) and keep their spelling as written, so that declarations can record how the file spells
//! each name and output can print it that way. Comments run from `;` to the end of
//! the line. The reader is iterative and refuses nesting deeper than [`MAX_DEPTH`], so the
//! recursive stages after it cannot overflow the stack whatever the input.

use crate::model::{SourceName, Span};

use super::error::ParseError;

/// The deepest nesting of parentheses accepted. Real HDDL files nest fewer than 15 levels.
pub const MAX_DEPTH: usize = 256;

/// An s-expression with the position of its first character.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Sexp {
    /// A symbol, variable, keyword or number: `text` lower-cased, `raw` as written.
    Atom {
        text: String,
        raw: String,
        span: Span,
    },
    /// A parenthesised list; `span` is its `(`.
    List { items: Vec<Sexp>, span: Span },
}

impl Sexp {
    pub(crate) fn span(&self) -> Span {
        match self {
            Sexp::Atom { span, .. } | Sexp::List { span, .. } => *span,
        }
    }

    pub(crate) fn as_atom(&self) -> Option<&str> {
        match self {
            Sexp::Atom { text, .. } => Some(text),
            Sexp::List { .. } => None,
        }
    }

    /// The atom as the file spells it (not case-folded).
    pub(crate) fn as_raw(&self) -> Option<&str> {
        match self {
            Sexp::Atom { raw, .. } => Some(raw),
            Sexp::List { .. } => None,
        }
    }

    pub(crate) fn as_list(&self) -> Option<&[Sexp]> {
        match self {
            Sexp::List { items, .. } => Some(items),
            Sexp::Atom { .. } => None,
        }
    }

    /// The head atom of a list, if it has one.
    pub(crate) fn head(&self) -> Option<&str> {
        self.as_list()
            .and_then(|items| items.first())
            .and_then(Sexp::as_atom)
    }

    /// A short description for error messages: the atom quoted, or the list's head.
    pub(crate) fn describe(&self) -> String {
        match self {
            Sexp::Atom { raw, .. } => format!("`{}`", shorten(raw)),
            Sexp::List { items, .. } => match items.first() {
                None => "`()`".to_string(),
                Some(Sexp::Atom { raw, .. }) => format!("`({} ...)`", shorten(raw)),
                Some(Sexp::List { .. }) => "a list of lists".to_string(),
            },
        }
    }
}

/// Cuts very long names in messages so one error stays one readable line.
pub(crate) fn shorten(text: &str) -> String {
    const MAX: usize = 80;
    if text.chars().count() <= MAX {
        text.to_string()
    } else {
        let cut: String = text.chars().take(MAX).collect();
        format!("{cut}…")
    }
}

fn is_delimiter(c: char) -> bool {
    c.is_whitespace() || c == '(' || c == ')' || c == ';'
}

/// The sections of a domain or problem (`(:action ...`, `(:init ...`): direct children of
/// `(define ...)`. One met deeper says that the section around it was never closed.
const SECTIONS: &[&str] = &[
    ":requirements",
    ":types",
    ":constants",
    ":predicates",
    ":shared-predicates",
    ":functions",
    ":geometric-tasks",
    ":task",
    ":method",
    ":action",
    ":domain",
    ":objects",
    ":htn",
    ":init",
    ":goal",
];

/// A list still open while reading.
struct Open {
    /// Its `(`.
    span: Span,
    /// Whether its `(` is the first thing on its line (its indentation means something).
    begins_line: bool,
    items: Vec<Sexp>,
}

/// Where the reader thinks a `(` that is never closed was opened, from the first evidence met.
enum Unclosed {
    /// A section (`(:method ...`) at `inner` lies inside the section opened at `outer`.
    Section {
        outer: Span,
        inner: Span,
        head: String,
    },
    /// A `(` at `inner`, first on its line, is indented no deeper than the line-opening `(`
    /// at `outer` that is still open around it.
    Indent { outer: Span, inner: Span },
}

/// The s-expressions of a file while it is parsed. Dropped normally, unless a limit of the
/// process's budget stopped the parsing: then the process is about to end, and freeing
/// millions of nodes one by one would take longer than the limit's slack.
pub(crate) struct Tree(pub Vec<Sexp>);

impl Drop for Tree {
    fn drop(&mut self) {
        if crate::budget::tripped().is_some() {
            std::mem::forget(std::mem::take(&mut self.0));
        }
    }
}

/// Why character `c` (a byte-order mark, a quote or a control character) cannot be read.
fn forbidden(c: char) -> String {
    match c {
        '\u{feff}' => "a UTF-8 byte-order mark (U+FEFF); HDDL files must not start with one \
                       (save the file as UTF-8 without BOM)"
            .to_string(),
        '"' => "quoted strings are not HDDL (expected a name, a `?variable` or a `:keyword`)"
            .to_string(),
        c => format!(
            "control character U+{:04X} is not allowed in HDDL \
             (expected text: names, `(`, `)`, spaces, tabs, newlines)",
            c as u32
        ),
    }
}

/// Consumes the rest of the atom that starts with `c` at byte `start`; returns the byte
/// where it ends and its width in characters.
fn atom_end(
    start: usize,
    c: char,
    chars: &mut std::iter::Peekable<std::str::CharIndices<'_>>,
) -> (usize, u32) {
    let mut end = start + c.len_utf8();
    let mut width: u32 = 1;
    while let Some(&(i, c)) = chars.peek() {
        if is_delimiter(c) || c == '"' || c == '\u{feff}' || c.is_control() {
            break;
        }
        end = i + c.len_utf8();
        width = width.saturating_add(1);
        chars.next();
    }
    (end, width)
}

/// Reads all top-level s-expressions of `text`.
pub(crate) fn read(text: &str, file: &SourceName) -> Result<Vec<Sexp>, ParseError> {
    let mut top: Vec<Sexp> = Vec::new();
    let mut stack: Vec<Open> = Vec::new();
    let mut line: u32 = 1;
    let mut col: u32 = 1;
    let mut at_line_start = true;
    let mut section_evidence: Option<Unclosed> = None;
    let mut indent_evidence: Option<Unclosed> = None;
    let mut chars = text.char_indices().peekable();
    let mut steps: u32 = 0;

    while let Some((start, c)) = chars.next() {
        let span = Span { line, col };
        // The process's budget (time, memory) is checked as the text is read: a huge file
        // stops at the limit, not after it is read whole.
        steps = steps.wrapping_add(1);
        if steps % 4096 == 0
            && let Some(limit) = crate::budget::check()
        {
            // The process stops: what was read is left to it, not freed node by node.
            std::mem::forget(top);
            std::mem::forget(stack);
            return Err(ParseError::new(
                file,
                span,
                crate::budget::message(limit, "reading this file"),
            ));
        }
        let begins_line = at_line_start;
        at_line_start = c == '\n' || (at_line_start && c.is_whitespace());
        match c {
            '\n' => {
                line = line.saturating_add(1);
                col = 1;
            }
            ';' => {
                // Skip to the end of the line; the newline itself is handled above.
                while let Some(&(_, c)) = chars.peek() {
                    if c == '\n' {
                        break;
                    }
                    chars.next();
                }
            }
            '(' => {
                if stack.len() >= MAX_DEPTH {
                    return Err(ParseError::new(
                        file,
                        span,
                        format!("parentheses nested deeper than {MAX_DEPTH} levels"),
                    ));
                }
                if begins_line
                    && indent_evidence.is_none()
                    && let Some(outer) = stack.iter().rev().find(|o| o.begins_line)
                    && outer.span.line < line
                    && outer.span.col >= col
                {
                    indent_evidence = Some(Unclosed::Indent {
                        outer: outer.span,
                        inner: span,
                    });
                }
                stack.push(Open {
                    span,
                    begins_line,
                    items: Vec::new(),
                });
                col = col.saturating_add(1);
            }
            ')' => {
                let Some(open) = stack.pop() else {
                    return Err(ParseError::new(
                        file,
                        span,
                        "unexpected `)` with no matching `(`",
                    ));
                };
                let list = Sexp::List {
                    items: open.items,
                    span: open.span,
                };
                match stack.last_mut() {
                    Some(parent) => parent.items.push(list),
                    None => top.push(list),
                }
                col = col.saturating_add(1);
            }
            '\u{feff}' | '"' => return Err(ParseError::new(file, span, forbidden(c))),
            c if c.is_control() && c != '\t' && c != '\r' => {
                return Err(ParseError::new(file, span, forbidden(c)));
            }
            c if c.is_whitespace() => col = col.saturating_add(1),
            _ => {
                let (end, width) = atom_end(start, c, &mut chars);
                let raw = text.get(start..end).unwrap_or_default();
                let atom = Sexp::Atom {
                    text: raw.to_ascii_lowercase(),
                    raw: raw.to_string(),
                    span,
                };
                // A section's keyword heading a list that lies inside another section.
                if section_evidence.is_none()
                    && stack.len() >= 3
                    && stack.last().is_some_and(|o| o.items.is_empty())
                    && let Some(Sexp::Atom { text: head, .. }) = Some(&atom)
                    && SECTIONS.contains(&head.as_str())
                    && let (Some(outer), Some(inner)) = (stack.get(1), stack.last())
                {
                    section_evidence = Some(Unclosed::Section {
                        outer: outer.span,
                        inner: inner.span,
                        head: shorten(raw),
                    });
                }
                match stack.last_mut() {
                    Some(parent) => parent.items.push(atom),
                    None => top.push(atom),
                }
                col = col.saturating_add(width);
            }
        }
    }

    if let Some(err) = unclosed(&stack, section_evidence, indent_evidence, file) {
        return Err(err);
    }
    Ok(top)
}

/// The error for lists left open at the end of the file (`stack`, outermost first), `None`
/// when none is: it points at the `(` most likely left unclosed, by the evidence gathered
/// while reading (a section inside another, or a `(` indented like an outer one).
fn unclosed(
    stack: &[Open],
    section_evidence: Option<Unclosed>,
    indent_evidence: Option<Unclosed>,
    file: &SourceName,
) -> Option<ParseError> {
    let innermost = stack.last()?;
    let open = stack.len();
    // Evidence counts only when it comes after the innermost list left open: a list opened
    // later and still open (a file cut short) is the better answer.
    let after = |e: &Unclosed| {
        let inner = match e {
            Unclosed::Section { inner, .. } | Unclosed::Indent { inner, .. } => *inner,
        };
        (inner.line, inner.col) > (innermost.span.line, innermost.span.col)
    };
    let evidence = section_evidence
        .filter(after)
        .or(indent_evidence.filter(after));
    let last_child = innermost.items.iter().rev().find_map(|i| match i {
        Sexp::List { span, .. } => Some(*span),
        Sexp::Atom { .. } => None,
    });
    let (at, message) = match evidence {
        Some(Unclosed::Section { outer, inner, head }) => (
            outer,
            format!(
                "this `(` is never closed: the section `({head}` at {}:{} lies inside it \
                 (end of file reached with {open} `(` open)",
                inner.line, inner.col
            ),
        ),
        Some(Unclosed::Indent { outer, inner }) => (
            outer,
            format!(
                "this `(` is probably never closed: the `(` at {}:{}, indented like it, \
                 lies inside it (end of file reached with {open} `(` open)",
                inner.line, inner.col
            ),
        ),
        None => match last_child {
            Some(last) if open == 1 => (
                innermost.span,
                format!(
                    "this `(` is never closed (end of file reached), or the list at {}:{}, \
                     the last in it, lacks its `)`",
                    last.line, last.col
                ),
            ),
            _ => (
                innermost.span,
                "this `(` is never closed (end of file reached)".to_string(),
            ),
        },
    };
    Some(ParseError::new(file, at, message))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;
    use std::sync::Arc;

    fn file() -> SourceName {
        Arc::new(PathBuf::from("t.hddl"))
    }

    #[test]
    fn reads_nested_lists_with_positions_and_lowercases() {
        let top = read("; c\n(A (b ?X) ;x\n\t:K)", &file()).unwrap();
        assert_eq!(top.len(), 1);
        let items = top[0].as_list().unwrap();
        assert_eq!(top[0].span(), Span { line: 2, col: 1 });
        assert_eq!(items[0].as_atom(), Some("a"));
        assert_eq!(items[0].as_raw(), Some("A"));
        assert_eq!(items[1].span(), Span { line: 2, col: 4 });
        assert_eq!(items[1].as_list().unwrap()[1].as_atom(), Some("?x"));
        assert_eq!(items[2].as_atom(), Some(":k"));
        assert_eq!(items[2].span(), Span { line: 3, col: 2 });
    }

    #[test]
    fn unbalanced_parentheses_are_located() {
        let e = read("(a\n  (b)", &file()).unwrap_err();
        assert_eq!((e.line, e.col), (1, 1));
        let e = read("(a))", &file()).unwrap_err();
        assert_eq!((e.line, e.col), (1, 4));
        // Truncated: the innermost open list.
        let e = read("(a\n  (b (c", &file()).unwrap_err();
        assert_eq!((e.line, e.col), (2, 6));
    }

    /// A missing `)` in the middle of a file is reported where the list that lacks it opens,
    /// not at the `(define` that the last `)` of the file leaves open.
    #[test]
    fn an_unclosed_paren_is_reported_where_it_was_opened() {
        // Indentation: the second action is indented like the first, yet lies inside it.
        let text = "(define (domain d)\n  (:action a\n    :parameters (?x\n    :effect (p))\n  (:action b :parameters ()))\n";
        let e = read(text, &file()).unwrap_err();
        assert_eq!((e.line, e.col), (2, 3), "{}", e.message);
        assert!(e.message.contains("5:3"), "{}", e.message);
        // On one line: a section inside a section.
        let text = "(define (domain d) (:predicates (p) (:action a :parameters ()))";
        let e = read(text, &file()).unwrap_err();
        assert_eq!((e.line, e.col), (1, 20), "{}", e.message);
        assert!(e.message.contains("`(:action` at 1:37"), "{}", e.message);
        // Indentation alone: `(q)` is indented like `(p ?x`, yet lies inside it.
        let text = "(define (domain d)\n  (:predicates\n    (p ?x\n    (q))\n  )\n";
        let e = read(text, &file()).unwrap_err();
        assert_eq!((e.line, e.col), (3, 5), "{}", e.message);
        assert!(
            e.message.contains("probably never closed: the `(` at 4:5"),
            "{}",
            e.message
        );
        // Misindented but balanced lists are no evidence: the truly unclosed one is named.
        let text = "(define (domain d)\n (:method m :subtasks (and\n (a)\n (b)))\n (:action x\n";
        let e = read(text, &file()).unwrap_err();
        assert_eq!((e.line, e.col), (5, 2), "{}", e.message);
    }

    #[test]
    fn bom_control_bytes_and_quotes_are_refused_with_positions() {
        let e = read("\u{feff}(a)", &file()).unwrap_err();
        assert!(e.message.contains("byte-order mark"), "{}", e.message);
        assert_eq!((e.line, e.col), (1, 1));
        let e = read("(a\n b\0c)", &file()).unwrap_err();
        assert!(e.message.contains("U+0000"), "{}", e.message);
        assert_eq!((e.line, e.col), (2, 3));
        let e = read("(a \"item\")", &file()).unwrap_err();
        assert!(e.message.contains("quoted strings"), "{}", e.message);
        assert_eq!((e.line, e.col), (1, 4));
        assert!(read("(a\t b\r\n c)", &file()).is_ok());
    }

    #[test]
    fn deep_nesting_is_an_error_not_a_stack_overflow() {
        let text = "(".repeat(100_000);
        let e = read(&text, &file()).unwrap_err();
        assert!(e.message.contains("nested deeper"));
        assert_eq!((e.line, e.col), (1, MAX_DEPTH as u32 + 1));
    }
}
