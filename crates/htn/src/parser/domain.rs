//! `(define (domain NAME) ...)`: declarations first, then method and action bodies, so a
//! method may name an action declared further down.

use std::collections::HashMap;

use crate::model::{
    Action, Domain, Formula, Method, OBJECT_TYPE, Signature, SourceName, Span, Spelling, Spellings,
    TypeDecl, TypedName,
};

use super::context::{Ctx, Result, Scope, Tables};
use super::error::ParseError;
use super::formula::Evaluable;
use super::sexpr::{Sexp, Tree, read, shorten};
use super::types::TypeTable;

/// The items of `(define (KIND NAME) ...)`, the name and its span, from the top level of a file.
pub(crate) fn define<'s>(
    top: &'s [Sexp],
    kind: &str,
    file: &SourceName,
) -> Result<(&'s [Sexp], String, Span)> {
    let expected = format!("expected `(define ({kind} NAME) ...)`");
    let Some(first) = top.first() else {
        return Err(ParseError::new(
            file,
            Span { line: 1, col: 1 },
            format!("empty file: {expected}"),
        ));
    };
    let items = match first {
        Sexp::List { items, .. } if first.head() == Some("define") => items,
        _ => {
            return Err(ParseError::new(
                file,
                first.span(),
                format!("{expected}, found {}", first.describe()),
            ));
        }
    };
    if let Some(extra) = top.get(1) {
        return Err(ParseError::new(
            file,
            extra.span(),
            format!(
                "unexpected {} after the end of the {kind} definition",
                extra.describe()
            ),
        ));
    }
    let header = items.get(1).ok_or_else(|| {
        ParseError::new(
            file,
            first.span(),
            format!("{expected}: the `({kind} NAME)` part is missing"),
        )
    })?;
    match header.as_list() {
        Some([k, name]) if k.as_atom() == Some(kind) => match name.as_atom() {
            Some(n) if super::context::is_name(n) && super::context::starts_with_letter(n) => {
                Ok((items, n.to_string(), name.span()))
            }
            _ => Err(ParseError::new(
                file,
                name.span(),
                format!("expected a {kind} name, found {}", name.describe()),
            )),
        },
        Some([k, ..]) if k.as_atom() == Some("problem") && kind == "domain" => {
            Err(ParseError::new(
                file,
                header.span(),
                "this is a problem file, but a domain was expected here",
            ))
        }
        Some([k, ..]) if k.as_atom() == Some("domain") && kind == "problem" => {
            Err(ParseError::new(
                file,
                header.span(),
                "this is a domain file, but a problem was expected here",
            ))
        }
        _ => Err(ParseError::new(
            file,
            header.span(),
            format!("expected `({kind} NAME)`, found {}", header.describe()),
        )),
    }
}

/// The keyword of a section `(:keyword ...)` and its items after the keyword.
pub(crate) fn section<'s>(
    item: &'s Sexp,
    file: &SourceName,
    what: &str,
) -> Result<(&'s str, &'s [Sexp])> {
    match item.as_list() {
        Some([Sexp::Atom { text, .. }, rest @ ..]) if text.starts_with(':') => Ok((text, rest)),
        _ => Err(ParseError::new(
            file,
            item.span(),
            format!(
                "expected a {what} section `(:keyword ...)`, found {}",
                item.describe()
            ),
        )),
    }
}

/// The sections of a domain by kind, file order kept within a kind.
struct Sections<'s> {
    /// The sections that may appear once, by keyword, with where each is.
    once: HashMap<&'s str, (Span, &'s [Sexp])>,
    task_decls: Vec<&'s Sexp>,
    methods: Vec<&'s Sexp>,
    actions: Vec<&'s Sexp>,
}

/// Sorts the domain's `items` (after `(define (domain ..)`) into [`Sections`]; a repeated
/// once-only section or an unknown keyword is an error.
fn sections<'s>(items: &'s [Sexp], file: &SourceName) -> Result<Sections<'s>> {
    let mut once: HashMap<&str, (Span, &[Sexp])> = HashMap::new();
    let mut task_decls: Vec<&Sexp> = Vec::new();
    let mut methods: Vec<&Sexp> = Vec::new();
    let mut actions: Vec<&Sexp> = Vec::new();
    for item in items {
        let (key, rest) = section(item, file, "domain")?;
        match key {
            ":task" => task_decls.push(item),
            ":method" => methods.push(item),
            ":action" => actions.push(item),
            ":requirements" | ":types" | ":constants" | ":predicates" | ":shared-predicates"
            | ":functions" | ":geometric-tasks" => {
                if let Some((first, _)) = once.get(key) {
                    return Err(ParseError::new(
                        file,
                        item.span(),
                        format!(
                            "a second `{key}` section (the first is at {}:{})",
                            first.line, first.col
                        ),
                    ));
                }
                once.insert(key, (item.span(), rest));
            }
            _ => {
                return Err(ParseError::new(
                    file,
                    item.span(),
                    format!(
                        "unknown domain section `{}`; expected :requirements :types :constants :predicates :shared-predicates :functions :geometric-tasks :task :method :action",
                        shorten(key)
                    ),
                ));
            }
        }
    }
    Ok(Sections {
        once,
        task_decls,
        methods,
        actions,
    })
}

/// The error for a second declaration of `name` as a `what`, the first at `first`.
fn already_declared(
    file: &SourceName,
    span: Span,
    what: &str,
    name: &str,
    first: Span,
) -> ParseError {
    ParseError::new(
        file,
        span,
        format!(
            "{what} `{}` is already declared at {}:{}",
            shorten(name),
            first.line,
            first.col
        ),
    )
}

/// Parses a domain. See [`super`] for the accepted language.
pub fn parse_domain(text: &str, source: SourceName) -> std::result::Result<Domain, ParseError> {
    let top = Tree(read(text, &source)?);
    let (items, name, _) = define(&top.0, "domain", &source)?;
    let file = &source;

    let mut domain = Domain {
        name,
        source: source.clone(),
        requirements: Vec::new(),
        types: Vec::new(),
        constants: Vec::new(),
        predicates: Vec::new(),
        shared_predicates: Vec::new(),
        functions: Vec::new(),
        tasks: Vec::new(),
        geometric_tasks: Vec::new(),
        methods: Vec::new(),
        actions: Vec::new(),
        spelling: Spellings::default(),
        warnings: Vec::new(),
    };

    let Sections {
        once,
        task_decls,
        methods,
        actions,
    } = sections(items.get(2..).unwrap_or_default(), file)?;
    let part = |key: &str| once.get(key).map(|(_, rest)| *rest);

    // Requirements must be known ones; they are recorded, not enforced (files often under- or
    // over-declare them).
    for r in part(":requirements").unwrap_or_default() {
        domain.requirements.push(requirement(r, file)?.to_string());
    }

    // Types, then a context whose tables know them.
    let empty_tables = Tables::new(file, &domain, &[])?;
    let mut ctx = Ctx {
        file,
        t: empty_tables,
        object_word: "constant",
    };
    domain.types = type_decls(
        &ctx,
        part(":types").unwrap_or_default(),
        &mut domain.warnings,
    )?;
    ctx.t = Tables::new(file, &domain, &[])?;

    domain.constants = ctx.typed_list(
        part(":constants").unwrap_or_default(),
        false,
        Some(&ctx.t.types),
    )?;

    let mut seen: HashMap<String, (Span, &'static str)> = HashMap::new();
    let mut declare = |sig: &Signature, kind: &'static str| -> Result<()> {
        if let Some((span, other)) = seen.get(&sig.name) {
            return Err(ParseError::new(
                file,
                sig.span,
                format!(
                    "`{}` is already declared as {} {other} at {}:{}",
                    shorten(&sig.name),
                    if other.starts_with(['a', 'e', 'i', 'o', 'u']) {
                        "an"
                    } else {
                        "a"
                    },
                    span.line,
                    span.col
                ),
            ));
        }
        seen.insert(sig.name.clone(), (sig.span, kind));
        Ok(())
    };
    for (key, kind) in [
        (":predicates", "predicate"),
        (":shared-predicates", "shared predicate"),
    ] {
        for p in part(key).unwrap_or_default() {
            let sig = ctx.signature(p, kind)?;
            declare(&sig, kind)?;
            if kind == "predicate" {
                domain.predicates.push(sig);
            } else {
                domain.shared_predicates.push(sig);
            }
        }
    }
    domain.functions = functions(&ctx, part(":functions").unwrap_or_default())?;
    let mut fseen: HashMap<String, Span> = HashMap::new();
    for f in &domain.functions {
        if let Some(s) = fseen.insert(f.name.clone(), f.span) {
            return Err(already_declared(file, f.span, "function", &f.name, s));
        }
    }
    // Geometric tasks live in their own namespace: only `evaluable` names them.
    let mut gseen: HashMap<String, Span> = HashMap::new();
    for g in part(":geometric-tasks").unwrap_or_default() {
        let sig = ctx.signature(g, "geometric task")?;
        if let Some(s) = gseen.insert(sig.name.clone(), sig.span) {
            return Err(already_declared(
                file,
                sig.span,
                "geometric task",
                &sig.name,
                s,
            ));
        }
        domain.geometric_tasks.push(sig);
    }

    // Tasks and actions share one namespace (a subtask names either).
    for t in &task_decls {
        let sig = task_decl(&ctx, t)?;
        declare(&sig, "task")?;
        domain.tasks.push(sig);
    }
    let mut action_sigs = Vec::with_capacity(actions.len());
    for a in &actions {
        let sig = action_signature(&ctx, a)?;
        declare(&sig, "action")?;
        action_sigs.push(sig);
    }
    ctx.t = Tables::new(file, &domain, &action_sigs)?;

    let mut mseen: HashMap<String, Span> = HashMap::new();
    for m in &methods {
        let method = method(&ctx, m)?;
        if let Some(s) = mseen.insert(method.name.clone(), method.span) {
            return Err(already_declared(
                file,
                method.span,
                "method",
                &method.name,
                s,
            ));
        }
        domain.methods.push(method);
    }
    for (a, sig) in actions.iter().zip(action_sigs) {
        domain.actions.push(action_body(&ctx, a, sig)?);
    }
    domain.spelling = domain_spellings(&part, &task_decls, &methods, &actions);
    Ok(domain)
}

/// How the domain file spells its declarations (read from the s-expressions once they parsed).
fn domain_spellings<'s>(
    part: &dyn Fn(&str) -> Option<&'s [Sexp]>,
    task_decls: &[&Sexp],
    methods: &[&Sexp],
    actions: &[&Sexp],
) -> Spellings {
    let mut sp = Spellings::default();
    for t in part(":types").unwrap_or_default() {
        if let Some(raw) = t.as_raw().filter(|r| *r != "-") {
            sp.types.declare(raw);
        }
    }
    spell_typed(part(":constants").unwrap_or_default(), &mut sp.objects);
    for key in [":predicates", ":shared-predicates", ":functions"] {
        for p in part(key).unwrap_or_default() {
            spell_at(p, 0, &mut sp.predicates);
        }
    }
    for t in task_decls.iter().chain(actions) {
        spell_at(t, 1, &mut sp.tasks);
    }
    for m in methods {
        spell_at(m, 1, &mut sp.methods);
    }
    sp
}

/// The requirements of PDDL 3.1 and of HDDL (with `:geometric`, this project's extension);
/// anything else (`:time-travel`) is refused, so that a typing error in a requirement, or a
/// requirement of a language htngtp does not read, is said at once.
pub const KNOWN_REQUIREMENTS: &[&str] = &[
    ":strips",
    ":typing",
    ":negative-preconditions",
    ":disjunctive-preconditions",
    ":equality",
    ":existential-preconditions",
    ":universal-preconditions",
    ":quantified-preconditions",
    ":conditional-effects",
    ":fluents",
    ":numeric-fluents",
    ":object-fluents",
    ":adl",
    ":durative-actions",
    ":duration-inequalities",
    ":continuous-effects",
    ":derived-predicates",
    ":timed-initial-literals",
    ":preferences",
    ":constraints",
    ":action-costs",
    ":hierarchy",
    ":method-preconditions",
    ":geometric",
];

/// A requirement `:name` of a `:requirements` section: a known one, else an error.
pub(crate) fn requirement<'s>(r: &'s Sexp, file: &SourceName) -> Result<&'s str> {
    match r.as_atom() {
        Some(a) if KNOWN_REQUIREMENTS.contains(&a) => Ok(a),
        Some(a) if a.starts_with(':') => Err(ParseError::new(
            file,
            r.span(),
            format!(
                "unknown requirement `{}`; known: {}",
                shorten(a),
                KNOWN_REQUIREMENTS.join(" ")
            ),
        )),
        _ => Err(ParseError::new(
            file,
            r.span(),
            format!("expected a requirement `:name`, found {}", r.describe()),
        )),
    }
}

/// Records the spellings of the names of a typed list `a b - t c` (not of its types).
pub(crate) fn spell_typed(items: &[Sexp], into: &mut Spelling) {
    let mut after_dash = false;
    for item in items {
        match item.as_raw() {
            Some("-") => after_dash = true,
            Some(raw) if !after_dash => into.declare(raw),
            _ => after_dash = false,
        }
    }
}

/// Records the spelling of the atom at `items[i]` of the list `item`, if there is one.
fn spell_at(item: &Sexp, i: usize, into: &mut Spelling) {
    if let Some(raw) = item.as_list().and_then(|l| l.get(i)).and_then(Sexp::as_raw) {
        into.declare(raw);
    }
}

/// `:types` entries `a b - c d - e f`; a type may get several parents over several entries.
fn type_decls(ctx: &Ctx, items: &[Sexp], warnings: &mut Vec<ParseError>) -> Result<Vec<TypeDecl>> {
    let entries = ctx.typed_list_allow_repeats(items)?;
    let mut decls: Vec<TypeDecl> = Vec::new();
    let mut index: HashMap<String, usize> = HashMap::new();
    for e in &entries {
        if e.name == OBJECT_TYPE {
            if e.ty != OBJECT_TYPE {
                return Err(ctx.err(e.span, "`object` is the root type and cannot have a parent"));
            }
            continue;
        }
        if e.name == e.ty {
            return Err(ctx.err(
                e.span,
                format!("type `{}` cannot be its own parent", shorten(&e.name)),
            ));
        }
        let i = *index.entry(e.name.clone()).or_insert_with(|| {
            decls.push(TypeDecl {
                name: e.name.clone(),
                parents: Vec::new(),
                span: e.span,
            });
            decls.len() - 1
        });
        if let Some(d) = decls.get_mut(i)
            && !d.parents.contains(&e.ty)
        {
            d.parents.push(e.ty.clone());
        }
    }
    // `object` as a parent says nothing when there are others.
    for d in &mut decls {
        if d.parents.len() > 1 {
            d.parents.retain(|p| p != OBJECT_TYPE);
        }
    }
    // A parent should be declared itself (`vehicle - object`), or be `object`. A parent named
    // nowhere else is declared by its use, below `object`, as PDDL planners and the IPC's
    // parser do (IPC 2020's AssemblyHierarchical relies on it), with a warning: it is often a
    // typing error.
    let mut implicit = Vec::new();
    for e in &entries {
        if e.ty != OBJECT_TYPE && !index.contains_key(&e.ty) {
            warnings.push(ctx.err(
                e.span,
                format!(
                    "the parent type `{}` of `{}` is not declared; taken as a subtype of \
                     `object` (declare it in `:types`, e.g. `{} - object`)",
                    shorten(&e.ty),
                    shorten(&e.name),
                    shorten(&e.ty)
                ),
            ));
            index.insert(e.ty.clone(), decls.len() + implicit.len());
            implicit.push(TypeDecl {
                name: e.ty.clone(),
                parents: vec![OBJECT_TYPE.to_string()],
                span: e.span,
            });
        }
    }
    decls.extend(implicit);
    TypeTable::new(&decls).map_err(|c| ctx.err(c.span, c.message()))?;
    Ok(decls)
}

/// `:functions` entries `(f ?x - t) ...`, each optionally followed by `- number`.
fn functions(ctx: &Ctx, items: &[Sexp]) -> Result<Vec<Signature>> {
    let mut out = Vec::new();
    let mut i = 0;
    while let Some(item) = items.get(i) {
        if item.as_atom() == Some("-") {
            let ty = ctx.next(items, i + 1, item.span(), "`number`")?;
            if out.is_empty() || ty.as_atom() != Some("number") {
                return Err(ctx.err(
                    ty.span(),
                    format!(
                        "functions must be of type `number`, found {}",
                        ty.describe()
                    ),
                ));
            }
            i += 2;
            continue;
        }
        out.push(ctx.signature(item, "function")?);
        i += 1;
    }
    Ok(out)
}

/// `(:task NAME :parameters (...))`.
fn task_decl(ctx: &Ctx, item: &Sexp) -> Result<Signature> {
    let items = item.as_list().unwrap_or_default();
    let name_item = ctx.next(items, 1, item.span(), "a task name")?;
    let name = ctx.declared_name(name_item, "a task name")?;
    let owner = format!("task `{}`", shorten(&name));
    let mut params = Vec::new();
    for (key, span, value) in ctx.keyword_pairs(
        items,
        2,
        &[":parameters", ":precondition", ":effect"],
        &owner,
    )? {
        match key {
            ":parameters" => params = parameters(ctx, value)?,
            _ => {
                return Err(ctx.err(
                    span,
                    format!("`{key}` on a task (hybrid planning) is not supported: htngtp reads hierarchical HDDL only"),
                ));
            }
        }
    }
    Ok(Signature {
        name,
        params,
        span: item.span(),
    })
}

fn parameters(ctx: &Ctx, value: &Sexp) -> Result<Vec<TypedName>> {
    let items = ctx.list(value, "a parameter list `(?x - type ...)`")?;
    ctx.typed_list(items, true, Some(&ctx.t.types))
}

const ACTION_KEYS: &[&str] = &[":parameters", ":precondition", ":effect"];

fn action_signature(ctx: &Ctx, item: &Sexp) -> Result<Signature> {
    let items = item.as_list().unwrap_or_default();
    let name_item = ctx.next(items, 1, item.span(), "an action name")?;
    let name = ctx.declared_name(name_item, "an action name")?;
    let owner = format!("action `{}`", shorten(&name));
    let mut params = Vec::new();
    for (key, _, value) in ctx.keyword_pairs(items, 2, ACTION_KEYS, &owner)? {
        if key == ":parameters" {
            params = parameters(ctx, value)?;
        }
    }
    Ok(Signature {
        name,
        params,
        span: item.span(),
    })
}

fn action_body(ctx: &Ctx, item: &Sexp, sig: Signature) -> Result<Action> {
    let items = item.as_list().unwrap_or_default();
    let owner = format!("action `{}`", shorten(&sig.name));
    let mut scope = Scope::new(&sig.params);
    let mut precondition = Formula::True;
    let mut effects = Vec::new();
    for (key, _, value) in ctx.keyword_pairs(items, 2, ACTION_KEYS, &owner)? {
        match key {
            ":precondition" => {
                precondition = ctx.formula(value, &mut scope, Evaluable::Allowed)?;
                let mut evaluables = Vec::new();
                collect_evaluables(&precondition, &mut evaluables);
                if let Some(second) = evaluables.get(1) {
                    return Err(ctx.err(
                        *second,
                        format!("{owner} has a second evaluable predicate: at most one per action"),
                    ));
                }
            }
            ":effect" => ctx.effect(value, &mut scope, &mut effects)?,
            _ => {}
        }
    }
    Ok(Action {
        name: sig.name,
        params: sig.params,
        precondition,
        effects,
        span: sig.span,
    })
}

/// Evaluable predicates can only sit in (nested) top-level conjunctions; the parser has
/// refused them anywhere else.
fn collect_evaluables(f: &Formula, out: &mut Vec<Span>) {
    match f {
        Formula::Evaluable { span, .. } => out.push(*span),
        Formula::And(parts) => parts.iter().for_each(|p| collect_evaluables(p, out)),
        _ => {}
    }
}

const METHOD_KEYS: &[&str] = &[
    ":parameters",
    ":task",
    ":precondition",
    ":constraints",
    ":subtasks",
    ":tasks",
    ":ordered-subtasks",
    ":ordered-tasks",
    ":ordering",
];

fn method(ctx: &Ctx, item: &Sexp) -> Result<Method> {
    let items = item.as_list().unwrap_or_default();
    let name_item = ctx.next(items, 1, item.span(), "a method name")?;
    let name = ctx.declared_name(name_item, "a method name")?;
    let owner = format!("method `{}`", shorten(&name));
    let pairs = ctx.keyword_pairs(items, 2, METHOD_KEYS, &owner)?;
    let get = |k: &str| {
        pairs
            .iter()
            .find(|(key, _, _)| *key == k)
            .map(|(_, _, v)| *v)
    };

    let params = match get(":parameters") {
        Some(v) => parameters(ctx, v)?,
        None => Vec::new(),
    };
    let mut scope = Scope::new(&params);

    let Some(task_item) = get(":task") else {
        return Err(ctx.err(item.span(), format!("{owner} has no `:task`")));
    };
    let task_items = ctx.list(task_item, "the decomposed task `(name ?x ...)`")?;
    let Some(task_head) = task_items.first() else {
        return Err(ctx.err(
            task_item.span(),
            "expected the decomposed task `(name ?x ...)`, found `()`",
        ));
    };
    let task = ctx.name(task_head, "a task name")?;
    let info = match ctx.t.tasks.get(&task) {
        Some(info) if !info.primitive => info,
        Some(_) => {
            return Err(ctx.err(
                task_head.span(),
                format!("`{}` is an action: a method decomposes an abstract task (declared with `:task`)", shorten(&task)),
            ));
        }
        None => {
            return Err(ctx.err(
                task_head.span(),
                format!("undeclared task `{}`", shorten(&task)),
            ));
        }
    };
    let task_args = ctx.args(
        &info.sig,
        "task",
        task_head.span(),
        task_items.get(1..).unwrap_or_default(),
        &scope,
    )?;

    let precondition = match get(":precondition") {
        Some(v) => ctx.formula(
            v,
            &mut scope,
            Evaluable::Forbidden("in a method precondition"),
        )?,
        None => Formula::True,
    };
    let constraints = match get(":constraints") {
        Some(v) => ctx.formula(v, &mut scope, Evaluable::Forbidden("in method constraints"))?,
        None => Formula::True,
    };

    let list = ctx.subtask_list(&pairs, &owner)?;
    let subtasks = ctx.task_network(list, get(":ordering"), &scope, &owner)?;

    Ok(Method {
        name,
        params,
        task,
        task_args,
        precondition,
        constraints,
        subtasks,
        span: item.span(),
    })
}

impl Ctx<'_> {
    /// Like [`Ctx::typed_list`] over names, but a name may come back (a type with several
    /// parents is written on several lines).
    fn typed_list_allow_repeats(&self, items: &[Sexp]) -> Result<Vec<TypedName>> {
        let mut out = Vec::new();
        let mut group = Vec::new();
        let mut i = 0;
        while let Some(item) = items.get(i) {
            if item.as_atom() == Some("-") && !group.is_empty() {
                let ty_item = self.next(items, i + 1, item.span(), "a type name")?;
                out.extend(
                    self.typed_list(
                        &[
                            std::mem::take(&mut group),
                            vec![item.clone(), ty_item.clone()],
                        ]
                        .concat(),
                        false,
                        None,
                    )?,
                );
                i += 2;
            } else {
                group.push(item.clone());
                i += 1;
            }
        }
        out.extend(self.typed_list(&group, false, None)?);
        Ok(out)
    }
}
