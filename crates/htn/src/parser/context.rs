//! What every part of the parser shares: the file for errors, the declared names of the domain
//! (and of the problem) for checking, and small helpers that read atoms, lists, typed lists
//! and arguments with precise errors.

use std::collections::HashMap;

use crate::model::{Domain, OBJECT_TYPE, Signature, SourceName, Span, Term, TypedName};

use super::error::ParseError;
use super::sexpr::{Sexp, shorten};
use super::types::TypeTable;

pub(crate) type Result<T> = std::result::Result<T, ParseError>;

/// A task or action signature with its kind.
#[derive(Clone, Debug)]
pub(crate) struct TaskInfo {
    pub sig: Signature,
    pub primitive: bool,
}

/// The declared names that bodies are checked against.
#[derive(Clone, Debug)]
pub(crate) struct Tables {
    pub types: TypeTable,
    /// Constants of the domain, and in a problem also its objects: name to type.
    pub objects: HashMap<String, String>,
    /// Predicates and shared predicates; the flag says shared.
    pub predicates: HashMap<String, (Signature, bool)>,
    pub functions: HashMap<String, Signature>,
    pub tasks: HashMap<String, TaskInfo>,
    pub geometric_tasks: HashMap<String, Signature>,
}

impl Tables {
    /// The tables of a domain whose declarations are filled in; `action_sigs` are the action
    /// signatures (the domain's actions may not be parsed yet).
    pub fn new(file: &SourceName, domain: &Domain, action_sigs: &[Signature]) -> Result<Tables> {
        let types = TypeTable::new(&domain.types)
            .map_err(|c| ParseError::new(file, c.span, c.message()))?;
        let objects = domain
            .constants
            .iter()
            .map(|c| (c.name.clone(), c.ty.clone()))
            .collect();
        let mut predicates = HashMap::new();
        for p in &domain.predicates {
            predicates.insert(p.name.clone(), (p.clone(), false));
        }
        for p in &domain.shared_predicates {
            predicates.insert(p.name.clone(), (p.clone(), true));
        }
        let functions = domain
            .functions
            .iter()
            .map(|f| (f.name.clone(), f.clone()))
            .collect();
        let mut tasks = HashMap::new();
        for t in &domain.tasks {
            tasks.insert(
                t.name.clone(),
                TaskInfo {
                    sig: t.clone(),
                    primitive: false,
                },
            );
        }
        for a in action_sigs {
            tasks.insert(
                a.name.clone(),
                TaskInfo {
                    sig: a.clone(),
                    primitive: true,
                },
            );
        }
        let geometric_tasks = domain
            .geometric_tasks
            .iter()
            .map(|g| (g.name.clone(), g.clone()))
            .collect();
        Ok(Tables {
            types,
            objects,
            predicates,
            functions,
            tasks,
            geometric_tasks,
        })
    }
}

/// Variables in scope: parameters, then quantified variables (innermost last).
#[derive(Clone, Debug, Default)]
pub(crate) struct Scope {
    /// Each variable's types, innermost binding last (a quantifier may shadow a parameter).
    types: HashMap<String, Vec<String>>,
    /// Variables in binding order, to undo bindings in [`Scope::truncate`].
    order: Vec<String>,
}

impl Scope {
    pub fn new(params: &[TypedName]) -> Scope {
        let mut scope = Scope::default();
        scope.push(params);
        scope
    }

    pub fn lookup(&self, var: &str) -> Option<&str> {
        self.types
            .get(var)
            .and_then(|ts| ts.last())
            .map(String::as_str)
    }

    pub fn len(&self) -> usize {
        self.order.len()
    }

    pub fn push(&mut self, vars: &[TypedName]) {
        for v in vars {
            self.types
                .entry(v.name.clone())
                .or_default()
                .push(v.ty.clone());
            self.order.push(v.name.clone());
        }
    }

    pub fn truncate(&mut self, len: usize) {
        while self.order.len() > len {
            if let Some(name) = self.order.pop()
                && let Some(ts) = self.types.get_mut(&name)
            {
                ts.pop();
                if ts.is_empty() {
                    self.types.remove(&name);
                }
            }
        }
    }
}

/// The parsing context: the file and the tables once they exist.
pub(crate) struct Ctx<'a> {
    pub file: &'a SourceName,
    pub t: Tables,
    /// "constant" in a domain, "object" in a problem: the word used in messages.
    pub object_word: &'static str,
}

/// Whether an atom is a plain name (of a predicate, task, object, ...).
pub(crate) fn is_name(s: &str) -> bool {
    !s.is_empty() && !s.starts_with('?') && !s.starts_with(':') && s != "-"
}

pub(crate) fn is_variable(s: &str) -> bool {
    s.len() > 1 && s.starts_with('?')
}

/// Whether a declared name starts as HDDL (and PDDL) requires: with a letter (`123` or `-x`
/// cannot name a type, object, predicate, task, action or method; `?1` cannot name a variable).
pub(crate) fn starts_with_letter(s: &str) -> bool {
    s.trim_start_matches('?')
        .chars()
        .next()
        .is_some_and(char::is_alphabetic)
}

/// The error for a declared name that does not start with a letter.
pub(crate) fn not_a_letter(what: &str, raw: &str) -> String {
    format!("{what} must start with a letter, found `{}`", shorten(raw))
}

/// A number as HDDL writes it: `-?digits(.digits)?`.
pub(crate) fn parse_number(s: &str) -> Option<f64> {
    let body = s.strip_prefix('-').unwrap_or(s);
    let (int, frac) = match body.split_once('.') {
        Some((i, f)) => (i, Some(f)),
        None => (body, None),
    };
    let digits = |d: &str| !d.is_empty() && d.bytes().all(|b| b.is_ascii_digit());
    if !digits(int) || frac.is_some_and(|f| !digits(f)) {
        return None;
    }
    s.parse::<f64>().ok().filter(|v| v.is_finite())
}

/// Whether an atom was meant as a number (starts like one), so a bad one gets a clear message.
pub(crate) fn looks_numeric(s: &str) -> bool {
    let body = s
        .strip_prefix('-')
        .or_else(|| s.strip_prefix('+'))
        .unwrap_or(s);
    let body = body.strip_prefix('.').unwrap_or(body);
    body.bytes().next().is_some_and(|b| b.is_ascii_digit())
}

/// `(name ?a ?b ...)` rendered for messages.
pub(crate) fn render_call(name: &str, args: &[Term]) -> String {
    let mut s = format!("({}", shorten(name));
    for a in args {
        s.push(' ');
        s.push_str(match a {
            Term::Var(v) | Term::Const(v) => v,
        });
    }
    s.push(')');
    s
}

impl<'a> Ctx<'a> {
    pub fn err(&self, span: Span, message: impl Into<String>) -> ParseError {
        ParseError::new(self.file, span, message)
    }

    pub fn atom<'s>(&self, s: &'s Sexp, what: &str) -> Result<&'s str> {
        s.as_atom()
            .ok_or_else(|| self.err(s.span(), format!("expected {what}, found {}", s.describe())))
    }

    pub fn list<'s>(&self, s: &'s Sexp, what: &str) -> Result<&'s [Sexp]> {
        s.as_list()
            .ok_or_else(|| self.err(s.span(), format!("expected {what}, found {}", s.describe())))
    }

    /// A plain name (not a variable, keyword or `-`).
    pub fn name(&self, s: &Sexp, what: &str) -> Result<String> {
        match s.as_atom() {
            Some(a) if is_name(a) => Ok(a.to_string()),
            _ => Err(self.err(s.span(), format!("expected {what}, found {}", s.describe()))),
        }
    }

    /// An error when the process's budget (time, memory) is spent, at `at`.
    pub fn within_budget(&self, at: Span, what: &str) -> Result<()> {
        match crate::budget::check() {
            Some(limit) => Err(self.err(at, crate::budget::message(limit, what))),
            None => Ok(()),
        }
    }

    /// A plain name that a declaration introduces: it must also start with a letter.
    pub fn declared_name(&self, s: &Sexp, what: &str) -> Result<String> {
        let name = self.name(s, what)?;
        if !starts_with_letter(&name) {
            return Err(self.err(s.span(), not_a_letter(what, &name)));
        }
        Ok(name)
    }

    /// The item after a keyword or `-`, or an error at `at` saying what is missing.
    pub fn next<'s>(&self, items: &'s [Sexp], i: usize, at: Span, what: &str) -> Result<&'s Sexp> {
        items
            .get(i)
            .ok_or_else(|| self.err(at, format!("expected {what} after this")))
    }

    /// A typed list `a b - t c - u d`: variables (`vars`) or names. Types are checked
    /// against `types` when given. Duplicate names are refused.
    pub fn typed_list(
        &self,
        items: &[Sexp],
        vars: bool,
        types: Option<&TypeTable>,
    ) -> Result<Vec<TypedName>> {
        let what = if vars { "a variable (`?x`)" } else { "a name" };
        let mut out: Vec<TypedName> = Vec::new();
        let mut pending = 0usize; // how many names at the end of `out` still lack a type
        let mut seen: HashMap<&str, usize> = HashMap::new();
        let mut i = 0;
        while let Some(item) = items.get(i) {
            if i % 4096 == 4095 {
                self.within_budget(item.span(), "reading a list of names")?;
            }
            let text = self.atom(item, what)?;
            if text == "-" {
                if pending == 0 {
                    return Err(self.err(item.span(), "`-` with no names before it"));
                }
                let ty_item = self.next(items, i + 1, item.span(), "a type name")?;
                if ty_item.head() == Some("either") {
                    return Err(self.err(
                        ty_item.span(),
                        "`either` types are not supported; declare a common super type",
                    ));
                }
                let ty = self.name(ty_item, "a type name")?;
                if types.is_none() && !starts_with_letter(&ty) {
                    return Err(self.err(ty_item.span(), not_a_letter("a type name", &ty)));
                }
                if let Some(types) = types
                    && !types.contains(&ty)
                {
                    return Err(self.err(
                        ty_item.span(),
                        format!("undeclared type `{}`", shorten(&ty)),
                    ));
                }
                let n = out.len();
                for tn in out.iter_mut().skip(n - pending) {
                    tn.ty = ty.clone();
                }
                pending = 0;
                i += 2;
                continue;
            }
            let ok = if vars {
                is_variable(text)
            } else {
                is_name(text)
            };
            if !ok {
                return Err(self.err(
                    item.span(),
                    format!("expected {what}, found `{}`", shorten(text)),
                ));
            }
            if !starts_with_letter(text) {
                return Err(self.err(item.span(), not_a_letter(what, text)));
            }
            if let Some(prev) = seen.get(text).and_then(|&i| out.get(i)) {
                return Err(self.err(
                    item.span(),
                    format!(
                        "`{}` is declared twice in this list (first at {}:{})",
                        shorten(text),
                        prev.span.line,
                        prev.span.col
                    ),
                ));
            }
            seen.insert(text, out.len());
            out.push(TypedName {
                name: text.to_string(),
                ty: OBJECT_TYPE.to_string(),
                span: item.span(),
            });
            pending += 1;
            i += 1;
        }
        Ok(out)
    }

    /// `(name ?a - t ...)`: a predicate, function, task or geometric task signature.
    pub fn signature(&self, s: &Sexp, what: &str) -> Result<Signature> {
        let items = self.list(s, &format!("a {what} declaration `(name ?x - type ...)`"))?;
        let Some(first) = items.first() else {
            return Err(self.err(s.span(), format!("empty {what} declaration")));
        };
        let name = self.declared_name(first, &format!("a {what} name"))?;
        let params = self.typed_list(
            items.get(1..).unwrap_or_default(),
            true,
            Some(&self.t.types),
        )?;
        Ok(Signature {
            name,
            params,
            span: s.span(),
        })
    }

    /// Splits `:key value :key value ...` (from `items[start..]`) into pairs, refusing
    /// unknown and repeated keys.
    pub fn keyword_pairs<'s>(
        &self,
        items: &'s [Sexp],
        start: usize,
        allowed: &[&str],
        owner: &str,
    ) -> Result<Vec<(&'s str, Span, &'s Sexp)>> {
        let mut out: Vec<(&'s str, Span, &'s Sexp)> = Vec::new();
        let mut i = start;
        while let Some(item) = items.get(i) {
            let key = match item.as_atom() {
                Some(k) if k.starts_with(':') => k,
                _ => {
                    return Err(self.err(
                        item.span(),
                        format!(
                            "expected a keyword ({}) in {owner}, found {}",
                            allowed.join(" "),
                            item.describe()
                        ),
                    ));
                }
            };
            if !allowed.contains(&key) {
                return Err(self.err(
                    item.span(),
                    format!(
                        "unknown keyword `{}` in {owner}; expected one of {}",
                        shorten(key),
                        allowed.join(" ")
                    ),
                ));
            }
            if out.iter().any(|(k, _, _)| *k == key) {
                return Err(self.err(item.span(), format!("`{key}` is given twice in {owner}")));
            }
            let value = self.next(items, i + 1, item.span(), &format!("a value for `{key}`"))?;
            out.push((key, item.span(), value));
            i += 2;
        }
        Ok(out)
    }

    /// A term and its type: a variable in scope, or a declared constant / object.
    pub fn term<'s>(&'s self, s: &Sexp, scope: &'s Scope) -> Result<(Term, &'s str)> {
        let text = self.atom(s, "a variable or a constant")?;
        if text.starts_with('?') {
            match scope.lookup(text) {
                Some(ty) => Ok((Term::Var(text.to_string()), ty)),
                None => Err(self.err(s.span(), format!("unbound variable `{}`", shorten(text)))),
            }
        } else if !is_name(text) {
            Err(self.err(
                s.span(),
                format!(
                    "expected a variable or a constant, found `{}`",
                    shorten(text)
                ),
            ))
        } else {
            match self.t.objects.get(text) {
                Some(ty) => Ok((Term::Const(text.to_string()), ty.as_str())),
                None => Err(self.err(
                    s.span(),
                    format!("undeclared {} `{}`", self.object_word, shorten(text)),
                )),
            }
        }
    }

    /// Checks the arguments of a call of `sig` (a `kind` such as "predicate") and returns them
    /// as terms. A variable must have a type compatible with the parameter's; a constant's
    /// type must be a subtype of it.
    pub fn args(
        &self,
        sig: &Signature,
        kind: &str,
        head_span: Span,
        args: &[Sexp],
        scope: &Scope,
    ) -> Result<Vec<Term>> {
        if args.len() != sig.params.len() {
            let params: Vec<String> = sig
                .params
                .iter()
                .map(|p| format!("{} - {}", p.name, p.ty))
                .collect();
            return Err(self.err(
                head_span,
                format!(
                    "{kind} `{}` takes {} argument{} ({}), found {}",
                    sig.name,
                    sig.params.len(),
                    if sig.params.len() == 1 { "" } else { "s" },
                    params.join(" "),
                    args.len()
                ),
            ));
        }
        let mut out = Vec::with_capacity(args.len());
        for (arg, param) in args.iter().zip(&sig.params) {
            let (term, ty) = self.term(arg, scope)?;
            let fits = match term {
                Term::Var(_) => self.t.types.compatible(ty, &param.ty),
                Term::Const(_) => self.t.types.is_subtype(ty, &param.ty),
            };
            if !fits {
                let shown = match &term {
                    Term::Var(v) | Term::Const(v) => v.clone(),
                };
                return Err(self.err(
                    arg.span(),
                    format!(
                        "argument `{}` of type `{ty}` does not fit parameter `{} - {}` of {kind} `{}`",
                        shorten(&shown),
                        param.name,
                        param.ty,
                        sig.name
                    ),
                ));
            }
            out.push(term);
        }
        Ok(out)
    }
}
