//! `(define (problem NAME) ...)`, checked against its domain.

use std::collections::HashMap;

use crate::model::{
    Domain, Formula, InitFact, InitValue, Problem, Signature, SourceName, Span, Spellings,
    TaskNetwork, Term,
};

use super::context::{Ctx, Result, Scope, Tables, is_name, looks_numeric, parse_number};
use super::domain::{define, section};
use super::error::ParseError;
use super::formula::Evaluable;
use super::sexpr::{Sexp, Tree, read, shorten};

/// Parses a problem of `domain`.
///
/// The problem's `(:domain NAME)` must name `domain` (an error otherwise: a problem read with
/// the wrong domain would be checked against the wrong declarations). Objects that repeat a
/// domain constant with the same type are accepted and left out of [`Problem::objects`].
pub fn parse_problem(
    text: &str,
    source: SourceName,
    domain: &Domain,
) -> std::result::Result<Problem, ParseError> {
    let top = Tree(read(text, &source)?);
    let (items, name, _) = define(&top.0, "problem", &source)?;
    let file = &source;
    let action_sigs: Vec<Signature> = domain
        .actions
        .iter()
        .map(|a| Signature {
            name: a.name.clone(),
            params: a.params.clone(),
            span: a.span,
        })
        .collect();
    let mut ctx = Ctx {
        file,
        t: Tables::new(&domain.source, domain, &action_sigs)?,
        object_word: "object",
    };

    let mut sections: HashMap<&str, (Span, &[Sexp])> = HashMap::new();
    for item in items.get(2..).unwrap_or_default() {
        let (key, rest) = section(item, file, "problem")?;
        if !matches!(
            key,
            ":domain" | ":requirements" | ":objects" | ":init" | ":htn" | ":goal"
        ) {
            return Err(ctx.err(
                item.span(),
                format!(
                    "unknown problem section `{}`; expected :domain :requirements :objects :htn :init :goal",
                    shorten(key)
                ),
            ));
        }
        if let Some((first, _)) = sections.get(key) {
            return Err(ctx.err(
                item.span(),
                format!(
                    "a second `{key}` section (the first is at {}:{})",
                    first.line, first.col
                ),
            ));
        }
        sections.insert(key, (item.span(), rest));
    }

    let Some((domain_span, domain_items)) = sections.get(":domain") else {
        return Err(ctx.err(
            items.first().map(Sexp::span).unwrap_or_default(),
            "the problem has no `(:domain NAME)` section",
        ));
    };
    let domain_name = match domain_items {
        [n] if n.as_atom().is_some_and(is_name) => n.as_atom().unwrap_or_default().to_string(),
        _ => return Err(ctx.err(*domain_span, "expected `(:domain NAME)`")),
    };
    if domain_name != domain.name {
        let at = domain_items.first().map(Sexp::span).unwrap_or(*domain_span);
        return Err(ctx.err(
            at,
            format!(
                "this problem is for domain `{}`, but the domain given ({}) is `{}`",
                shorten(&domain_name),
                domain.source.display(),
                shorten(&domain.name)
            ),
        ));
    }
    for r in sections
        .get(":requirements")
        .map(|s| s.1)
        .unwrap_or_default()
    {
        super::domain::requirement(r, ctx.file)?;
    }

    // Objects join the domain's constants.
    let mut spelling = Spellings::default();
    super::domain::spell_typed(
        sections.get(":objects").map(|s| s.1).unwrap_or_default(),
        &mut spelling.objects,
    );
    let declared = ctx.typed_list(
        sections.get(":objects").map(|s| s.1).unwrap_or_default(),
        false,
        Some(&ctx.t.types),
    )?;
    let mut objects = Vec::with_capacity(declared.len());
    for o in declared {
        match ctx.t.objects.get(&o.name) {
            Some(ty) if *ty == o.ty => continue,
            Some(ty) => {
                return Err(ctx.err(
                    o.span,
                    format!(
                        "object `{}` of type `{}` is also a constant of the domain with type `{ty}`",
                        shorten(&o.name),
                        o.ty
                    ),
                ));
            }
            None => {
                ctx.t.objects.insert(o.name.clone(), o.ty.clone());
                objects.push(o);
            }
        }
    }

    let (init, init_values) = init(&ctx, sections.get(":init").map(|s| s.1).unwrap_or_default())?;
    let htn = match sections.get(":htn") {
        Some((_, rest)) => network(&ctx, rest)?,
        None => TaskNetwork::default(),
    };
    let goal = match sections.get(":goal").map(|s| s.1) {
        None | Some([]) => Formula::True,
        Some([g]) => ctx.formula(g, &mut Scope::default(), Evaluable::Forbidden("in a goal"))?,
        Some([_, extra, ..]) => {
            return Err(ctx.err(
                extra.span(),
                "`:goal` takes one condition (use `(and ...)`)",
            ));
        }
    };

    Ok(Problem {
        name,
        domain_name,
        source: source.clone(),
        objects,
        init,
        init_values,
        htn,
        goal,
        spelling,
    })
}

/// `:init`: ground facts of ordinary predicates and `(= (f objects) number)`.
fn init(ctx: &Ctx, items: &[Sexp]) -> Result<(Vec<InitFact>, Vec<InitValue>)> {
    let mut facts = Vec::with_capacity(items.len());
    let mut values: Vec<InitValue> = Vec::new();
    let mut value_at: HashMap<(String, Vec<String>), Span> = HashMap::new();
    let scope = Scope::default();
    let ground = |terms: Vec<Term>| -> Vec<String> {
        terms
            .into_iter()
            .map(|t| match t {
                Term::Var(v) | Term::Const(v) => v,
            })
            .collect()
    };
    for (k, item) in items.iter().enumerate() {
        if k % 4096 == 4095 {
            ctx.within_budget(item.span(), "reading the initial state")?;
        }
        let parts = ctx.list(item, "a fact `(p ...)` or a value `(= (f ...) n)`")?;
        let Some(first) = parts.first() else {
            return Err(ctx.err(item.span(), "expected a fact `(p ...)`, found `()`"));
        };
        let head = ctx.atom(first, "a predicate name")?;
        let args = parts.get(1..).unwrap_or_default();
        if head == "=" {
            let [target, value] = ctx.exactly::<2>(
                args,
                item.span(),
                "an initial value is written `(= (f ...) number)`",
            )?;
            let fluent = ctx.fluent(target, &scope)?;
            let v = match value.as_atom() {
                Some(t) => match parse_number(t) {
                    Some(v) => v,
                    None if looks_numeric(t) => {
                        return Err(ctx.err(value.span(), format!("bad number `{}`", shorten(t))));
                    }
                    None => {
                        return Err(ctx.err(
                            value.span(),
                            format!("expected a number, found `{}`", shorten(t)),
                        ));
                    }
                },
                None => {
                    return Err(ctx.err(
                        value.span(),
                        format!("expected a number, found {}", value.describe()),
                    ));
                }
            };
            let args = ground(fluent.args);
            if let Some(prev) =
                value_at.insert((fluent.function.clone(), args.clone()), item.span())
            {
                return Err(ctx.err(
                    item.span(),
                    format!(
                        "`({} {})` already has a value (at {}:{})",
                        fluent.function,
                        args.join(" "),
                        prev.line,
                        prev.col
                    ),
                ));
            }
            values.push(InitValue {
                function: fluent.function,
                args,
                value: v,
                span: item.span(),
            });
            continue;
        }
        match ctx.t.predicates.get(head) {
            Some((_, true)) => {
                return Err(ctx.err(
                    first.span(),
                    format!(
                        "shared predicate `{}` in `:init`: its facts come from the geometric scene, not from the problem",
                        shorten(head)
                    ),
                ));
            }
            Some((sig, false)) => {
                let args = ctx.args(sig, "predicate", first.span(), args, &scope)?;
                facts.push(InitFact {
                    predicate: head.to_string(),
                    args: ground(args),
                    span: first.span(),
                });
            }
            None => {
                let message = if head == "not" {
                    "`not` in `:init`: the initial state lists only true facts (closed world)"
                        .to_string()
                } else if ctx.t.functions.contains_key(head) {
                    format!(
                        "`{}` is a numeric fluent: give its value as `(= ({} ...) number)`",
                        shorten(head),
                        shorten(head)
                    )
                } else {
                    format!("undeclared predicate `{}`", shorten(head))
                };
                return Err(ctx.err(first.span(), message));
            }
        }
    }
    Ok((facts, values))
}

const HTN_KEYS: &[&str] = &[
    ":parameters",
    ":subtasks",
    ":tasks",
    ":ordered-subtasks",
    ":ordered-tasks",
    ":ordering",
    ":constraints",
];

/// `(:htn :parameters (...) :subtasks ... :ordering ... :constraints ...)`.
fn network(ctx: &Ctx, items: &[Sexp]) -> Result<TaskNetwork> {
    // keyword_pairs counts from the section's first item; `items` already starts after `:htn`.
    let owner = "the initial task network";
    let pairs = ctx.keyword_pairs(items, 0, HTN_KEYS, owner)?;
    let get = |k: &str| {
        pairs
            .iter()
            .find(|(key, _, _)| *key == k)
            .map(|(_, _, v)| *v)
    };
    let params = match get(":parameters") {
        Some(v) => {
            let items = ctx.list(v, "a parameter list `(?x - type ...)`")?;
            ctx.typed_list(items, true, Some(&ctx.t.types))?
        }
        None => Vec::new(),
    };
    let mut scope = Scope::new(&params);
    let list = ctx.subtask_list(&pairs, owner)?;
    let subtasks = ctx.task_network(list, get(":ordering"), &scope, owner)?;
    let constraints = match get(":constraints") {
        Some(v) => ctx.formula(
            v,
            &mut scope,
            Evaluable::Forbidden("in task network constraints"),
        )?,
        None => Formula::True,
    };
    Ok(TaskNetwork {
        params,
        subtasks,
        constraints,
    })
}
