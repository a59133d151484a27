//! The validator's own world: a name-based state (facts and fluent values), formula
//! evaluation with quantifiers over the objects of a type, and action execution.

use std::collections::HashMap;

use crate::model::{
    CompareOp, Domain, Effect, Formula, Method, NumExpr, NumericEffectOp, OBJECT_TYPE, Problem,
    Term, TypedName,
};

use super::{Env, FastMap, FastSet, Key};

/// The domain's types and objects, for checking arguments and ranging quantifiers.
pub(super) struct World<'a> {
    domain: &'a Domain,
    /// Object to its types (declared type and all ancestors, and `object`); objects of one
    /// declared type share the set.
    types: FastMap<String, std::rc::Rc<FastSet<String>>>,
    /// Type to its objects.
    objects_of: FastMap<String, Vec<String>>,
}

/// The state: facts as `[predicate, args..]` keys, indexed by predicate; fluent values.
#[derive(Clone, Default)]
pub(super) struct St {
    facts: FastMap<String, FastSet<Key>>,
    pub(super) values: FastMap<Key, f64>,
}

impl St {
    pub(super) fn contains(&self, k: &Key) -> bool {
        self.facts.get(&k[0]).is_some_and(|s| s.contains(k))
    }
    pub(super) fn insert(&mut self, k: Key) {
        self.facts.entry(k[0].clone()).or_default().insert(k);
    }
    pub(super) fn remove(&mut self, k: &Key) {
        if let Some(s) = self.facts.get_mut(&k[0]) {
            s.remove(k);
        }
    }
}

/// The fact or fluent key `[head, args..]`.
pub(super) fn key(head: &str, args: &[String]) -> Key {
    let mut k = Vec::with_capacity(args.len() + 1);
    k.push(head.to_string());
    k.extend(args.iter().cloned());
    k
}

impl<'a> World<'a> {
    pub(super) fn new(domain: &'a Domain, problem: &Problem) -> World<'a> {
        let mut parents: HashMap<&str, Vec<&str>> = HashMap::new();
        for t in &domain.types {
            parents
                .entry(t.name.as_str())
                .or_default()
                .extend(t.parents.iter().map(String::as_str));
        }
        // Each declared type's ancestor set, computed once.
        let mut ancestors: HashMap<&str, std::rc::Rc<FastSet<String>>> = HashMap::new();
        let mut types: FastMap<String, std::rc::Rc<FastSet<String>>> = FastMap::default();
        for o in domain.constants.iter().chain(&problem.objects) {
            let set = ancestors.entry(o.ty.as_str()).or_insert_with(|| {
                let mut set = FastSet::default();
                let mut todo = vec![o.ty.as_str(), OBJECT_TYPE];
                while let Some(t) = todo.pop() {
                    if set.insert(t.to_string())
                        && let Some(ps) = parents.get(t)
                    {
                        todo.extend(ps.iter().copied());
                    }
                }
                std::rc::Rc::new(set)
            });
            // A name declared twice (a constant and an object) has the types of both.
            match types.get_mut(&o.name) {
                Some(had) => {
                    let mut both: FastSet<String> = (**had).clone();
                    both.extend(set.iter().cloned());
                    *had = std::rc::Rc::new(both);
                }
                None => {
                    types.insert(o.name.clone(), set.clone());
                }
            }
        }
        let mut objects_of: FastMap<String, Vec<String>> = FastMap::default();
        let mut names: Vec<&String> = types.keys().collect();
        names.sort();
        for o in names {
            for t in types[o].iter() {
                objects_of.entry(t.clone()).or_default().push(o.clone());
            }
        }
        World {
            domain,
            types,
            objects_of,
        }
    }

    pub(super) fn is_of(&self, o: &str, ty: &str) -> bool {
        self.types.get(o).is_some_and(|ts| ts.contains(ty))
    }

    pub(super) fn objects(&self, ty: &str) -> &[String] {
        self.objects_of.get(ty).map_or(&[], Vec::as_slice)
    }

    pub(super) fn term<'e>(&self, t: &'e Term, env: &'e Env) -> Option<&'e str> {
        match t {
            Term::Const(c) => Some(c),
            Term::Var(v) => env.get(v).map(String::as_str),
        }
    }

    pub(super) fn ground(&self, head: &str, args: &[Term], env: &Env) -> Option<Key> {
        let mut k = vec![head.to_string()];
        for a in args {
            k.push(self.term(a, env)?.to_string());
        }
        Some(k)
    }

    pub(super) fn num(&self, st: &St, e: &NumExpr, env: &Env) -> Option<f64> {
        Some(match e {
            NumExpr::Number(x) => *x,
            NumExpr::Fluent(f) => *st.values.get(&self.ground(&f.function, &f.args, env)?)?,
            NumExpr::Binary(op, a, b) => {
                let (a, b) = (self.num(st, a, env)?, self.num(st, b, env)?);
                op.apply(a, b)?
            }
            NumExpr::Neg(a) => -self.num(st, a, env)?,
        })
    }

    /// Whether `f` holds; variables not in `env` are unbound (an error of the model: false).
    pub(super) fn holds(&self, st: &St, f: &Formula, env: &mut Env) -> bool {
        match f {
            Formula::True => true,
            Formula::Atom(a) => self
                .ground(&a.predicate, &a.args, env)
                .is_some_and(|k| st.contains(&k)),
            Formula::Equal(a, b, _) => match (self.term(a, env), self.term(b, env)) {
                (Some(x), Some(y)) => x == y,
                _ => false,
            },
            Formula::Not(x) => !self.holds(st, x, env),
            Formula::And(xs) => xs.iter().all(|x| self.holds(st, x, env)),
            Formula::Or(xs) => xs.iter().any(|x| self.holds(st, x, env)),
            Formula::Imply(a, b) => !self.holds(st, a, env) || self.holds(st, b, env),
            Formula::Exists(vars, body) => self.quantify(st, vars, body, env, true),
            Formula::Forall(vars, body) => !self.quantify_not(st, vars, body, env),
            Formula::Compare(op, a, b, _) => match (self.num(st, a, env), self.num(st, b, env)) {
                (Some(x), Some(y)) => match op {
                    CompareOp::Lt => x < y,
                    CompareOp::Le => x <= y,
                    CompareOp::Eq => x == y,
                    CompareOp::Ge => x >= y,
                    CompareOp::Gt => x > y,
                },
                _ => false,
            },
            // Geometric truth is not checked here: the plan's geometric solution attests it.
            Formula::Evaluable { .. } => true,
        }
    }

    /// Whether some binding of `vars` makes `body` hold.
    pub(super) fn quantify(
        &self,
        st: &St,
        vars: &[TypedName],
        body: &Formula,
        env: &mut Env,
        want: bool,
    ) -> bool {
        let Some((v, rest)) = vars.split_first() else {
            return self.holds(st, body, env) == want;
        };
        let saved = env.get(&v.name).cloned();
        let mut found = false;
        for o in self.objects(&v.ty) {
            env.insert(v.name.clone(), o.clone());
            if self.quantify(st, rest, body, env, want) {
                found = true;
                break;
            }
        }
        match saved {
            Some(s) => env.insert(v.name.clone(), s),
            None => env.remove(&v.name),
        };
        found
    }

    /// Whether some binding of `vars` makes every formula of `body` hold. Variables are bound
    /// through the facts of a positive atom that mentions them when there is one (the same
    /// answer as trying every object of their types, much faster), else by their types.
    pub(super) fn quantify_all(
        &self,
        st: &St,
        vars: &[TypedName],
        body: &[&Formula],
        env: &mut Env,
    ) -> bool {
        let mut conj: Vec<&Formula> = Vec::new();
        fn flatten<'f>(f: &'f Formula, out: &mut Vec<&'f Formula>) {
            match f {
                Formula::And(xs) => xs.iter().for_each(|x| flatten(x, out)),
                Formula::True => {}
                f => out.push(f),
            }
        }
        body.iter().for_each(|f| flatten(f, &mut conj));
        self.bind(st, vars, &conj, env)
    }

    pub(super) fn bind(
        &self,
        st: &St,
        vars: &[TypedName],
        conj: &[&Formula],
        env: &mut Env,
    ) -> bool {
        let unbound: Vec<&TypedName> = vars.iter().filter(|v| !env.contains_key(&v.name)).collect();
        if unbound.is_empty() {
            return conj.iter().all(|f| self.holds(st, f, env));
        }
        let is_unbound = |t: &Term, env: &Env| matches!(t, Term::Var(v) if !env.contains_key(v) && unbound.iter().any(|u| &u.name == v));
        // A positive atom over some unbound variable binds them from the facts.
        let atom = conj.iter().find_map(|f| match f {
            Formula::Atom(a) if a.args.iter().any(|t| is_unbound(t, env)) => Some(a),
            _ => None,
        });
        if let Some(a) = atom {
            let Some(facts) = st.facts.get(&a.predicate) else {
                return false;
            };
            for fact in facts {
                if fact.len() != a.args.len() + 1 {
                    continue;
                }
                let mut newly: Vec<String> = Vec::new();
                let mut ok = true;
                for (t, val) in a.args.iter().zip(&fact[1..]) {
                    match t {
                        Term::Const(c) => ok = c == val,
                        Term::Var(v) => match env.get(v) {
                            Some(b) => ok = b == val,
                            None => {
                                let ty =
                                    unbound.iter().find(|u| &u.name == v).map(|u| u.ty.as_str());
                                ok = ty.is_some_and(|ty| self.is_of(val, ty));
                                if ok {
                                    env.insert(v.clone(), val.clone());
                                    newly.push(v.clone());
                                }
                            }
                        },
                    }
                    if !ok {
                        break;
                    }
                }
                let found = ok && self.bind(st, vars, conj, env);
                for v in newly {
                    env.remove(&v);
                }
                if found {
                    return true;
                }
            }
            return false;
        }
        let v = unbound[0];
        for o in self.objects(&v.ty) {
            env.insert(v.name.clone(), o.clone());
            if self.bind(st, vars, conj, env) {
                env.remove(&v.name);
                return true;
            }
        }
        env.remove(&v.name);
        false
    }

    /// Whether some binding of `vars` makes `body` false.
    pub(super) fn quantify_not(
        &self,
        st: &St,
        vars: &[TypedName],
        body: &Formula,
        env: &mut Env,
    ) -> bool {
        self.quantify(st, vars, body, env, false)
    }

    pub(super) fn method_pre_holds(&self, st: &St, m: &Method, env: &Env) -> bool {
        let free: Vec<TypedName> = m
            .params
            .iter()
            .filter(|p| !env.contains_key(&p.name))
            .cloned()
            .collect();
        let mut env = env.clone();
        self.quantify_all(st, &free, &[&m.precondition, &m.constraints], &mut env)
    }

    pub(super) fn execute(&self, st: &mut St, a: &crate::plan::PlanAction) -> Result<(), String> {
        let Some(act) = self.domain.actions.iter().find(|x| x.name == a.name) else {
            return Err("not an action of the domain".into());
        };
        if act.params.len() != a.args.len() {
            return Err(format!(
                "has {} arguments, the domain declares {}",
                a.args.len(),
                act.params.len()
            ));
        }
        let mut env = Env::default();
        for (p, x) in act.params.iter().zip(&a.args) {
            if !self.is_of(x, &p.ty) {
                return Err(format!("`{x}` is not an object of type `{}`", p.ty));
            }
            env.insert(p.name.clone(), x.clone());
        }
        if !self.holds(st, &act.precondition, &mut env) {
            return Err("its precondition does not hold".into());
        }
        let gs = has_evaluable(&act.precondition);
        if gs && a.geometric.is_none() {
            return Err(
                "a GS action without its geometric solution (the competition format does not carry shared literals; check the JSON plan)".into(),
            );
        }
        let mut adds = Vec::new();
        let mut dels = Vec::new();
        let mut values = Vec::new();
        self.effects(
            st,
            &act.effects,
            &mut env,
            &mut adds,
            &mut dels,
            &mut values,
        )?;
        for (k, v) in values {
            st.values.insert(k, v);
        }
        for k in &dels {
            st.remove(k);
        }
        for k in adds {
            st.insert(k);
        }
        if let Some(g) = &a.geometric {
            for x in &g.delete {
                st.remove(&key(&x.predicate, &x.args));
            }
            for x in &g.add {
                st.insert(key(&x.predicate, &x.args));
            }
        }
        Ok(())
    }

    pub(super) fn effects(
        &self,
        st: &St,
        effs: &[Effect],
        env: &mut Env,
        adds: &mut Vec<Key>,
        dels: &mut Vec<Key>,
        values: &mut Vec<(Key, f64)>,
    ) -> Result<(), String> {
        for e in effs {
            match e {
                Effect::Add(x) => adds.extend(self.ground(&x.predicate, &x.args, env)),
                Effect::Delete(x) => dels.extend(self.ground(&x.predicate, &x.args, env)),
                Effect::Forall(vars, inner) => {
                    self.forall_effects(st, vars, inner, env, adds, dels, values)?
                }
                Effect::When(c, inner) => {
                    if self.holds(st, c, env) {
                        self.effects(st, inner, env, adds, dels, values)?;
                    }
                }
                Effect::Numeric(op, f, e) => {
                    let k = self
                        .ground(&f.function, &f.args, env)
                        .ok_or("an effect on an unbound fluent")?;
                    let x = self.num(st, e, env).ok_or_else(|| {
                        format!(
                            "effect on ({}): the value reads an undefined fluent",
                            k.join(" ")
                        )
                    })?;
                    let cur = st.values.get(&k).copied();
                    let v = match (op, cur) {
                        (NumericEffectOp::Assign, _) => x,
                        (_, None) => {
                            return Err(format!("effect on undefined fluent ({})", k.join(" ")));
                        }
                        (_, Some(c)) => op.apply(c, x).ok_or("scale-down by zero")?,
                    };
                    values.push((k, v));
                }
            }
        }
        Ok(())
    }

    #[allow(clippy::too_many_arguments)]
    pub(super) fn forall_effects(
        &self,
        st: &St,
        vars: &[TypedName],
        inner: &[Effect],
        env: &mut Env,
        adds: &mut Vec<Key>,
        dels: &mut Vec<Key>,
        values: &mut Vec<(Key, f64)>,
    ) -> Result<(), String> {
        let Some((v, rest)) = vars.split_first() else {
            return self.effects(st, inner, env, adds, dels, values);
        };
        for o in self.objects(&v.ty) {
            env.insert(v.name.clone(), o.clone());
            self.forall_effects(st, rest, inner, env, adds, dels, values)?;
        }
        env.remove(&v.name);
        Ok(())
    }
}

pub(super) fn has_evaluable(f: &Formula) -> bool {
    match f {
        Formula::Evaluable { .. } => true,
        Formula::And(xs) => xs.iter().any(has_evaluable),
        _ => false,
    }
}
