//! The type hierarchy of a domain: subtype tests over types with several parents.

use std::collections::HashMap;

use crate::model::{OBJECT_TYPE, Span, TypeDecl};

use super::sexpr::shorten;

/// The most types a domain may declare. Real domains have fewer than a hundred; the bound keeps
/// the ancestor sets (one bit per type pair) small whatever the input.
pub const MAX_TYPES: usize = 10_000;

/// The declared types of a domain with, for each, the set of all its ancestors.
///
/// `object` is always present and is an ancestor of every type. Built once per domain; the
/// parser uses it for type checking, and the planner may use it to enumerate objects by type.
#[derive(Clone, Debug)]
pub struct TypeTable {
    index: HashMap<String, usize>,
    names: Vec<String>,
    /// `ancestors[i]` is a bit set holding `i` itself, every parent, grand-parent, ..., and
    /// `object` (bit 0).
    ancestors: Vec<Vec<u64>>,
}

/// Why a type table could not be built: a cycle (the type is its own ancestor) or too many
/// types; with the type's name and where it was declared.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TypeTableError {
    pub name: String,
    pub span: Span,
    /// True when the problem is [`MAX_TYPES`] rather than a cycle.
    pub too_many: bool,
}

impl TypeTableError {
    /// The error message (one line).
    pub fn message(&self) -> String {
        if self.too_many {
            format!("more than {MAX_TYPES} types (at `{}`)", shorten(&self.name))
        } else {
            format!(
                "type `{}` is its own ancestor (cycle in `:types`)",
                shorten(&self.name)
            )
        }
    }
}

fn has(bits: &[u64], i: usize) -> bool {
    bits.get(i / 64).is_some_and(|w| w & (1 << (i % 64)) != 0)
}

impl TypeTable {
    /// Builds the table; parents that are not declared themselves become direct subtypes of
    /// `object` (as in PDDL, naming a type as a parent declares it).
    pub fn new(decls: &[TypeDecl]) -> Result<Self, TypeTableError> {
        let mut index: HashMap<String, usize> = HashMap::new();
        let mut names: Vec<String> = vec![OBJECT_TYPE.to_string()];
        let mut spans: Vec<Span> = vec![Span::default()];
        let mut parents: Vec<Vec<usize>> = vec![Vec::new()];
        index.insert(OBJECT_TYPE.to_string(), 0);
        for decl in decls {
            let mut ids = Vec::with_capacity(decl.parents.len() + 1);
            for name in std::iter::once(&decl.name).chain(&decl.parents) {
                let i = match index.get(name) {
                    Some(&i) => i,
                    None => {
                        if names.len() >= MAX_TYPES {
                            return Err(TypeTableError {
                                name: name.clone(),
                                span: decl.span,
                                too_many: true,
                            });
                        }
                        names.push(name.clone());
                        spans.push(decl.span);
                        parents.push(Vec::new());
                        index.insert(name.clone(), names.len() - 1);
                        names.len() - 1
                    }
                };
                ids.push(i);
            }
            if let Some((&child, ps)) = ids.split_first()
                && let Some(slot) = parents.get_mut(child)
            {
                slot.extend(ps.iter().copied().filter(|&p| p != 0));
            }
        }

        // Parents before children (Kahn's algorithm); what is left lies on or below a cycle.
        let n = names.len();
        let mut children: Vec<Vec<usize>> = vec![Vec::new(); n];
        let mut waiting: Vec<usize> = parents.iter().map(Vec::len).collect();
        for (child, ps) in parents.iter().enumerate() {
            for &p in ps {
                if let Some(c) = children.get_mut(p) {
                    c.push(child);
                }
            }
        }
        let mut order: Vec<usize> = (0..n).filter(|&i| waiting.get(i) == Some(&0)).collect();
        let mut k = 0;
        while let Some(&t) = order.get(k) {
            k += 1;
            for &c in children.get(t).into_iter().flatten() {
                if let Some(w) = waiting.get_mut(c) {
                    *w -= 1;
                    if *w == 0 {
                        order.push(c);
                    }
                }
            }
        }
        if order.len() < n {
            // Walk up through types still waiting until one comes back: it is on a cycle.
            let left = |i: usize| waiting.get(i).is_some_and(|w| *w > 0);
            let mut at = (0..n).find(|&i| left(i)).unwrap_or(0);
            let mut seen = vec![false; n];
            while let Some(false) = seen.get(at).copied() {
                if let Some(s) = seen.get_mut(at) {
                    *s = true;
                }
                match parents
                    .get(at)
                    .and_then(|ps| ps.iter().copied().find(|&p| left(p)))
                {
                    Some(p) => at = p,
                    None => break,
                }
            }
            return Err(TypeTableError {
                name: names.get(at).cloned().unwrap_or_default(),
                span: spans.get(at).copied().unwrap_or_default(),
                too_many: false,
            });
        }

        let words = n.div_ceil(64);
        let mut ancestors: Vec<Vec<u64>> = vec![Vec::new(); n];
        for &t in &order {
            let mut bits = vec![0u64; words];
            for &p in parents.get(t).into_iter().flatten() {
                if let Some(pb) = ancestors.get(p) {
                    for (b, w) in bits.iter_mut().zip(pb) {
                        *b |= w;
                    }
                }
            }
            for i in [0, t] {
                if let Some(w) = bits.get_mut(i / 64) {
                    *w |= 1 << (i % 64);
                }
            }
            if let Some(slot) = ancestors.get_mut(t) {
                *slot = bits;
            }
        }
        Ok(TypeTable {
            index,
            names,
            ancestors,
        })
    }

    /// Whether `name` is a type of the domain (`object` always is).
    pub fn contains(&self, name: &str) -> bool {
        self.index.contains_key(name)
    }

    /// All type names, `object` first.
    pub fn names(&self) -> &[String] {
        &self.names
    }

    /// Whether every object of type `sub` is also of type `sup` (reflexive).
    pub fn is_subtype(&self, sub: &str, sup: &str) -> bool {
        if sub == sup {
            return self.contains(sub);
        }
        match (self.index.get(sub), self.index.get(sup)) {
            (Some(&a), Some(&b)) => self.ancestors.get(a).is_some_and(|s| has(s, b)),
            _ => false,
        }
    }

    /// Whether some object could have both types: one is a subtype of the other, or they
    /// share a common subtype. A variable of type `a` may be passed where `b` is expected iff
    /// this holds (the binding is then checked against the object's type at planning time).
    pub fn compatible(&self, a: &str, b: &str) -> bool {
        let (Some(&a), Some(&b)) = (self.index.get(a), self.index.get(b)) else {
            return false;
        };
        self.ancestors.iter().any(|anc| has(anc, a) && has(anc, b))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn decl(name: &str, parents: &[&str]) -> TypeDecl {
        TypeDecl {
            name: name.into(),
            parents: parents.iter().map(|p| p.to_string()).collect(),
            span: Span::default(),
        }
    }

    #[test]
    fn several_parents_and_implicit_parent_types() {
        let t = TypeTable::new(&[
            decl("truck", &["vehicle"]),
            decl("truck", &["container"]),
            decl("car", &["vehicle"]),
        ])
        .unwrap();
        assert!(t.is_subtype("truck", "vehicle"));
        assert!(t.is_subtype("truck", "container"));
        assert!(t.is_subtype("truck", "object"));
        assert!(!t.is_subtype("vehicle", "truck"));
        assert!(t.compatible("vehicle", "container"), "common subtype truck");
        assert!(!t.compatible("car", "container"));
        assert!(t.contains("container"));
    }

    #[test]
    fn cycles_are_refused() {
        let e = TypeTable::new(&[decl("a", &["b"]), decl("b", &["a"])]).unwrap_err();
        assert_eq!(e.name, "a");
        assert!(!e.too_many);
        let e =
            TypeTable::new(&[decl("x", &["a"]), decl("a", &["b"]), decl("b", &["a"])]).unwrap_err();
        assert!(e.name == "a" || e.name == "b", "{e:?}");
    }

    #[test]
    fn a_long_chain_is_cheap_and_too_many_types_are_refused() {
        let chain: Vec<TypeDecl> = (0..5000)
            .map(|i| decl(&format!("t{i}"), &[&format!("t{}", i + 1)]))
            .collect();
        let t = TypeTable::new(&chain).unwrap();
        assert!(t.is_subtype("t0", "t5000"));
        assert!(!t.is_subtype("t5000", "t0"));
        let many: Vec<TypeDecl> = (0..MAX_TYPES)
            .map(|i| decl(&format!("t{i}"), &[]))
            .collect();
        assert!(TypeTable::new(&many).unwrap_err().too_many);
    }
}
