//! The type hierarchy of a domain: subtype tests over types with several parents.

use std::collections::{HashMap, HashSet};

use crate::model::{OBJECT_TYPE, Span, TypeDecl};

/// The declared types of a domain with, for each, the set of all its ancestors.
///
/// `object` is always present and is an ancestor of every type. Built once per domain; the
/// parser uses it for type checking, and the planner may use it to enumerate objects by type.
#[derive(Clone, Debug)]
pub struct TypeTable {
    index: HashMap<String, usize>,
    names: Vec<String>,
    /// `ancestors[i]` holds `i` itself, every parent, grand-parent, ..., and `object`.
    ancestors: Vec<HashSet<usize>>,
}

/// A cycle in the type declarations: the type that is its own ancestor and where it was declared.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TypeCycle {
    pub name: String,
    pub span: Span,
}

impl TypeTable {
    /// Builds the table; parents that are not declared themselves become direct subtypes of
    /// `object` (as in PDDL, naming a type as a parent declares it).
    pub fn new(decls: &[TypeDecl]) -> Result<Self, TypeCycle> {
        let mut index: HashMap<String, usize> = HashMap::new();
        let mut names: Vec<String> = vec![OBJECT_TYPE.to_string()];
        let mut spans: Vec<Span> = vec![Span::default()];
        index.insert(OBJECT_TYPE.to_string(), 0);
        let mut intern = |name: &str, span: Span, names: &mut Vec<String>| -> usize {
            if let Some(&i) = index.get(name) {
                return i;
            }
            let i = names.len();
            names.push(name.to_string());
            spans.push(span);
            index.insert(name.to_string(), i);
            i
        };
        let mut parents: Vec<Vec<usize>> = vec![Vec::new()];
        for decl in decls {
            let child = intern(&decl.name, decl.span, &mut names);
            let ps: Vec<usize> = decl
                .parents
                .iter()
                .map(|p| intern(p, decl.span, &mut names))
                .collect();
            if parents.len() < names.len() {
                parents.resize(names.len(), Vec::new());
            }
            if let Some(slot) = parents.get_mut(child) {
                slot.extend(ps);
            }
        }
        parents.resize(names.len(), Vec::new());

        let mut ancestors = Vec::with_capacity(names.len());
        for start in 0..names.len() {
            let mut seen: HashSet<usize> = HashSet::new();
            seen.insert(start);
            seen.insert(0);
            let mut todo: Vec<usize> = parents.get(start).cloned().unwrap_or_default();
            while let Some(t) = todo.pop() {
                if t == start {
                    return Err(TypeCycle {
                        name: names.get(start).cloned().unwrap_or_default(),
                        span: spans.get(start).copied().unwrap_or_default(),
                    });
                }
                if seen.insert(t) {
                    todo.extend(parents.get(t).into_iter().flatten().copied());
                }
            }
            ancestors.push(seen);
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
            (Some(&a), Some(&b)) => self.ancestors.get(a).is_some_and(|s| s.contains(&b)),
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
        self.ancestors
            .iter()
            .any(|anc| anc.contains(&a) && anc.contains(&b))
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
    }
}
