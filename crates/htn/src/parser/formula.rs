//! Conditions (preconditions, constraints, goals), effects and numeric expressions, checked
//! against the declared predicates, functions and geometric tasks as they are read.

use crate::model::{
    ArithOp, CompareOp, Effect, FluentTerm, Formula, NumExpr, NumericEffectOp, Term, TypedName,
};

use super::context::{Ctx, Result, Scope, is_name, looks_numeric, parse_number};
use super::sexpr::{Sexp, shorten};

/// Where an evaluable predicate may appear.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Evaluable {
    /// In the top-level conjunction of an action's precondition.
    Allowed,
    /// Anywhere else; the reason completes "evaluable predicate ...".
    Forbidden(&'static str),
}

impl Evaluable {
    /// The context below a connective: still forbidden for the outer reason, or forbidden
    /// because of this connective.
    fn under(self, reason: &'static str) -> Evaluable {
        match self {
            Evaluable::Allowed => Evaluable::Forbidden(reason),
            forbidden => forbidden,
        }
    }
}

impl Ctx<'_> {
    /// A condition.
    pub fn formula(&self, s: &Sexp, scope: &mut Scope, ev: Evaluable) -> Result<Formula> {
        let items = self.list(s, "a condition in parentheses")?;
        let Some(first) = items.first() else {
            return Ok(Formula::True);
        };
        let Some(head) = first.as_atom() else {
            return Err(self.err(
                first.span(),
                "expected a predicate or a connective (and, or, not, ...) at the start of this list, found a list",
            ));
        };
        let args = items.get(1..).unwrap_or_default();
        let span = s.span();
        match head {
            "and" => {
                if args.is_empty() {
                    return Ok(Formula::True);
                }
                let parts = args
                    .iter()
                    .map(|a| self.formula(a, scope, ev))
                    .collect::<Result<Vec<_>>>()?;
                Ok(Formula::And(parts))
            }
            "or" => {
                let parts = args
                    .iter()
                    .map(|a| self.formula(a, scope, ev.under("under `or`")))
                    .collect::<Result<Vec<_>>>()?;
                Ok(Formula::Or(parts))
            }
            "not" => {
                let [inner] = self.exactly::<1>(args, span, "`not` takes one condition")?;
                let f = self.formula(inner, scope, ev.under("under `not`"))?;
                Ok(Formula::Not(Box::new(f)))
            }
            "imply" => {
                let [a, b] = self.exactly::<2>(args, span, "`imply` takes two conditions")?;
                let a = self.formula(a, scope, ev.under("under `imply`"))?;
                let b = self.formula(b, scope, ev.under("under `imply`"))?;
                Ok(Formula::Imply(Box::new(a), Box::new(b)))
            }
            "exists" | "forall" => {
                let [vars, body] = self.exactly::<2>(
                    args,
                    span,
                    &format!("`{head}` takes a variable list and a condition"),
                )?;
                let vars = self.quantified(vars)?;
                let mark = scope.len();
                scope.push(&vars);
                let reason = if head == "exists" {
                    "under `exists`"
                } else {
                    "under `forall`"
                };
                let body = self.formula(body, scope, ev.under(reason));
                scope.truncate(mark);
                let body = Box::new(body?);
                Ok(if head == "exists" {
                    Formula::Exists(vars, body)
                } else {
                    Formula::Forall(vars, body)
                })
            }
            "=" => {
                let [a, b] = self.exactly::<2>(args, span, "`=` takes two operands")?;
                let term_like = |x: &Sexp| x.as_atom().is_some_and(|t| !looks_numeric(t));
                if term_like(a) && term_like(b) {
                    let (ta, _) = self.term(a, scope)?;
                    let (tb, _) = self.term(b, scope)?;
                    Ok(Formula::Equal(ta, tb, span))
                } else {
                    let ea = self.num_expr(a, scope)?;
                    let eb = self.num_expr(b, scope)?;
                    Ok(Formula::Compare(CompareOp::Eq, ea, eb, span))
                }
            }
            "<" | "<=" | ">" | ">=" => {
                let op = match head {
                    "<" => CompareOp::Lt,
                    "<=" => CompareOp::Le,
                    ">" => CompareOp::Gt,
                    _ => CompareOp::Ge,
                };
                let [a, b] = self.exactly::<2>(
                    args,
                    span,
                    &format!("`{head}` takes two numeric expressions"),
                )?;
                let ea = self.num_expr(a, scope)?;
                let eb = self.num_expr(b, scope)?;
                Ok(Formula::Compare(op, ea, eb, span))
            }
            "evaluable" => {
                if let Evaluable::Forbidden(reason) = ev {
                    return Err(self.err(
                        span,
                        format!(
                            "evaluable predicate {reason}: it is allowed only positively, as a conjunct of the top-level `and` of an action's precondition"
                        ),
                    ));
                }
                let [call] = self.exactly::<1>(
                    args,
                    span,
                    "`evaluable` takes one geometric task call `(t ?a ...)`",
                )?;
                let call_items = self.list(call, "a geometric task call `(t ?a ...)`")?;
                let Some(name_item) = call_items.first() else {
                    return Err(self.err(
                        call.span(),
                        "expected a geometric task call `(t ?a ...)`, found `()`",
                    ));
                };
                let name = self.name(name_item, "a geometric task name")?;
                let Some(sig) = self.t.geometric_tasks.get(&name) else {
                    return Err(self.err(
                        name_item.span(),
                        format!(
                            "undeclared geometric task `{}` (declare it in `:geometric-tasks`)",
                            shorten(&name)
                        ),
                    ));
                };
                let args = self.args(
                    sig,
                    "geometric task",
                    name_item.span(),
                    call_items.get(1..).unwrap_or_default(),
                    scope,
                )?;
                Ok(Formula::Evaluable {
                    task: name,
                    args,
                    span,
                })
            }
            "sortof" => self.sortof(args, span, scope),
            _ => {
                let atom = self.atom_call(first, head, args, scope)?;
                Ok(Formula::Atom(atom))
            }
        }
    }

    /// `(sortof ?v - T)` (a type test, used in method constraints) is the same as
    /// `(exists (?w - T) (= ?w ?v))`; it is stored that way. The fresh variable's name has a
    /// space, so it cannot clash with a variable of the file.
    fn sortof(&self, args: &[Sexp], span: crate::model::Span, scope: &Scope) -> Result<Formula> {
        let [v, dash, ty] =
            self.exactly::<3>(args, span, "`sortof` is written `(sortof ?x - type)`")?;
        if dash.as_atom() != Some("-") {
            return Err(self.err(
                dash.span(),
                format!("expected `-`, found {}", dash.describe()),
            ));
        }
        let (term, _) = self.term(v, scope)?;
        let ty_name = self.name(ty, "a type name")?;
        if !self.t.types.contains(&ty_name) {
            return Err(self.err(
                ty.span(),
                format!("undeclared type `{}`", shorten(&ty_name)),
            ));
        }
        let fresh = "?sortof witness".to_string();
        Ok(Formula::Exists(
            vec![TypedName {
                name: fresh.clone(),
                ty: ty_name,
                span: v.span(),
            }],
            Box::new(Formula::Equal(Term::Var(fresh), term, span)),
        ))
    }

    /// `(p args)` with `p` an ordinary or shared predicate.
    fn atom_call(
        &self,
        first: &Sexp,
        head: &str,
        args: &[Sexp],
        scope: &Scope,
    ) -> Result<crate::model::Atom> {
        if let Some((sig, _)) = self.t.predicates.get(head) {
            let args = self.args(sig, "predicate", first.span(), args, scope)?;
            return Ok(crate::model::Atom {
                predicate: head.to_string(),
                args,
                span: first.span(),
            });
        }
        let message = if self.t.functions.contains_key(head) {
            format!(
                "`{}` is a numeric fluent, not a predicate: compare it, e.g. `(> ({} ...) 0)`",
                shorten(head),
                shorten(head)
            )
        } else if self.t.tasks.contains_key(head) {
            format!("`{}` is a task or action, not a predicate", shorten(head))
        } else if self.t.geometric_tasks.contains_key(head) {
            format!(
                "`{}` is a geometric task; ask about it with `(evaluable ({} ...))`",
                shorten(head),
                shorten(head)
            )
        } else if is_name(head) {
            format!("undeclared predicate `{}`", shorten(head))
        } else {
            format!(
                "expected a predicate or a connective (and, or, not, ...), found `{}`",
                shorten(head)
            )
        };
        Err(self.err(first.span(), message))
    }

    /// The variable list of a quantifier.
    pub fn quantified(&self, vars: &Sexp) -> Result<Vec<TypedName>> {
        let items = self.list(vars, "a variable list `(?x - type ...)`")?;
        self.typed_list(items, true, Some(&self.t.types))
    }

    /// Exactly `N` arguments, or an error at `span` with `message`.
    pub fn exactly<'s, const N: usize>(
        &self,
        args: &'s [Sexp],
        span: crate::model::Span,
        message: &str,
    ) -> Result<&'s [Sexp; N]> {
        <&[Sexp; N]>::try_from(args)
            .map_err(|_| self.err(span, format!("{message}, found {} argument(s)", args.len())))
    }

    /// A numeric expression.
    pub fn num_expr(&self, s: &Sexp, scope: &Scope) -> Result<NumExpr> {
        let items = match s {
            Sexp::Atom { text, span, .. } => {
                return match parse_number(text) {
                    Some(v) => Ok(NumExpr::Number(v)),
                    None if looks_numeric(text) => {
                        Err(self.err(*span, format!("bad number `{}`", shorten(text))))
                    }
                    None => Err(self.err(
                        *span,
                        format!(
                            "expected a number or a numeric expression `(f ...)`, found `{}`",
                            shorten(text)
                        ),
                    )),
                };
            }
            Sexp::List { items, .. } => items,
        };
        let Some(first) = items.first() else {
            return Err(self.err(s.span(), "expected a numeric expression, found `()`"));
        };
        let head = self.atom(first, "a function name or an arithmetic operator")?;
        let args = items.get(1..).unwrap_or_default();
        let span = s.span();
        let op = match head {
            "+" => Some(ArithOp::Add),
            "-" => Some(ArithOp::Sub),
            "*" => Some(ArithOp::Mul),
            "/" => Some(ArithOp::Div),
            _ => None,
        };
        if let Some(op) = op {
            return match (op, args) {
                (ArithOp::Sub, [a]) => Ok(NumExpr::Neg(Box::new(self.num_expr(a, scope)?))),
                (_, [a, b]) => Ok(NumExpr::Binary(
                    op,
                    Box::new(self.num_expr(a, scope)?),
                    Box::new(self.num_expr(b, scope)?),
                )),
                // `+` and `*` are associative: fold longer argument lists from the left.
                (ArithOp::Add | ArithOp::Mul, [a, rest @ ..]) if !rest.is_empty() => {
                    let mut acc = self.num_expr(a, scope)?;
                    for r in rest {
                        acc =
                            NumExpr::Binary(op, Box::new(acc), Box::new(self.num_expr(r, scope)?));
                    }
                    Ok(acc)
                }
                _ => Err(self.err(
                    span,
                    format!(
                        "`{head}` takes two numeric expressions, found {} argument(s)",
                        args.len()
                    ),
                )),
            };
        }
        Ok(NumExpr::Fluent(self.fluent(s, scope)?))
    }

    /// `(f args)` with `f` a declared function.
    pub fn fluent(&self, s: &Sexp, scope: &Scope) -> Result<FluentTerm> {
        let items = self.list(s, "a numeric fluent `(f ...)`")?;
        let Some(first) = items.first() else {
            return Err(self.err(s.span(), "expected a numeric fluent `(f ...)`, found `()`"));
        };
        let head = self.atom(first, "a function name")?;
        let Some(sig) = self.t.functions.get(head) else {
            let message = if self.t.predicates.contains_key(head) {
                format!("`{}` is a predicate, not a numeric fluent", shorten(head))
            } else {
                format!(
                    "undeclared function `{}` (declare it in `:functions`)",
                    shorten(head)
                )
            };
            return Err(self.err(first.span(), message));
        };
        let args = self.args(
            sig,
            "function",
            first.span(),
            items.get(1..).unwrap_or_default(),
            scope,
        )?;
        Ok(FluentTerm {
            function: head.to_string(),
            args,
            span: first.span(),
        })
    }

    /// An effect, appended to `out` (conjunctions are flattened).
    pub fn effect(&self, s: &Sexp, scope: &mut Scope, out: &mut Vec<Effect>) -> Result<()> {
        let items = self.list(s, "an effect in parentheses")?;
        let Some(first) = items.first() else {
            return Ok(());
        };
        let Some(head) = first.as_atom() else {
            return Err(self.err(first.span(), "expected a predicate or `and`, `not`, `forall`, `when`, `increase`, ... at the start of this list, found a list"));
        };
        let args = items.get(1..).unwrap_or_default();
        let span = s.span();
        match head {
            "and" => {
                for a in args {
                    self.effect(a, scope, out)?;
                }
            }
            "not" => {
                let [inner] = self.exactly::<1>(args, span, "`not` takes one atom")?;
                out.push(Effect::Delete(self.effect_atom(inner, scope)?));
            }
            "forall" => {
                let [vars, body] =
                    self.exactly::<2>(args, span, "`forall` takes a variable list and an effect")?;
                let vars = self.quantified(vars)?;
                let mark = scope.len();
                scope.push(&vars);
                let mut inner = Vec::new();
                let r = self.effect(body, scope, &mut inner);
                scope.truncate(mark);
                r?;
                out.push(Effect::Forall(vars, inner));
            }
            "when" => {
                let [cond, body] =
                    self.exactly::<2>(args, span, "`when` takes a condition and an effect")?;
                let cond =
                    self.formula(cond, scope, Evaluable::Forbidden("in a `when` condition"))?;
                let mut inner = Vec::new();
                self.effect(body, scope, &mut inner)?;
                out.push(Effect::When(cond, inner));
            }
            "increase" | "decrease" | "assign" | "scale-up" | "scale-down" => {
                let op = match head {
                    "increase" => NumericEffectOp::Increase,
                    "decrease" => NumericEffectOp::Decrease,
                    "assign" => NumericEffectOp::Assign,
                    "scale-up" => NumericEffectOp::ScaleUp,
                    _ => NumericEffectOp::ScaleDown,
                };
                let [target, value] = self.exactly::<2>(
                    args,
                    span,
                    &format!("`{head}` takes a fluent and a numeric expression"),
                )?;
                let target = self.fluent(target, scope)?;
                let value = self.num_expr(value, scope)?;
                out.push(Effect::Numeric(op, target, value));
            }
            "evaluable" => {
                return Err(self.err(
                    span,
                    "evaluable predicate in an effect: it is allowed only in an action's precondition",
                ));
            }
            _ => out.push(Effect::Add(self.effect_atom(s, scope)?)),
        }
        Ok(())
    }

    /// An atom an effect adds or deletes: an ordinary (not shared) predicate.
    fn effect_atom(&self, s: &Sexp, scope: &Scope) -> Result<crate::model::Atom> {
        let items = self.list(s, "an atom `(p ...)`")?;
        let Some(first) = items.first() else {
            return Err(self.err(s.span(), "expected an atom `(p ...)`, found `()`"));
        };
        let head = self.atom(first, "a predicate name")?;
        if let Some((_, true)) = self.t.predicates.get(head) {
            return Err(self.err(
                first.span(),
                format!(
                    "shared predicate `{}` cannot be changed by an action effect: its facts come from geometry",
                    shorten(head)
                ),
            ));
        }
        self.atom_call(first, head, items.get(1..).unwrap_or_default(), scope)
    }
}
