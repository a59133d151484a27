//! Names to ids: types (with each type's objects, subtypes included), objects, tasks
//! (abstract and primitive), predicates; an unknown name is a model error.

use crate::budget::Watch;
use std::collections::{HashMap, HashSet};

use crate::model::{OBJECT_TYPE, Problem, TypedName};

use super::super::{Limit, PlanError};
use super::{Builder, CTask};

impl Builder<'_> {
    pub(super) fn type_id(&mut self, name: &str) -> u32 {
        if let Some(&t) = self.type_ids.get(name) {
            return t;
        }
        let t = self.c.type_objects.len() as u32;
        self.type_ids.insert(name.to_string(), t);
        self.c.type_objects.push(Vec::new());
        t
    }

    pub(super) fn types_and_objects(
        &mut self,
        problem: &Problem,
        watch: &mut Watch,
    ) -> Result<(), PlanError> {
        self.type_id(OBJECT_TYPE);
        let mut parents: HashMap<String, Vec<String>> = HashMap::new();
        for t in &self.domain.types {
            self.type_id(&t.name);
            parents
                .entry(t.name.clone())
                .or_default()
                .extend(t.parents.iter().cloned());
        }
        let all: Vec<&TypedName> = self
            .domain
            .constants
            .iter()
            .chain(problem.objects.iter())
            .collect();
        // (type, object) pairs recorded: a linear `contains` per object was quadratic (160k
        // objects of one type took seconds, past any time limit).
        let mut member: HashSet<(usize, u32)> = HashSet::new();
        for (k, o) in all.into_iter().enumerate() {
            if k % 4096 == 4095
                && let Some(limit) = watch.check()
            {
                return Err(PlanError::Stopped(limit));
            }
            let id = match self.c.object_ids.get(&o.name) {
                Some(&id) => id,
                None => {
                    let id = self.c.objects.len() as u32;
                    self.c.objects.push(o.name.clone());
                    self.c.object_ids.insert(o.name.clone(), id);
                    id
                }
            };
            // The object is of its type and of every ancestor.
            let mut todo = vec![o.ty.clone(), OBJECT_TYPE.to_string()];
            let mut seen: Vec<String> = Vec::new();
            while let Some(t) = todo.pop() {
                if seen.contains(&t) {
                    continue;
                }
                let tid = self.type_id(&t) as usize;
                if member.insert((tid, id)) {
                    self.c.type_objects[tid].push(id);
                }
                if let Some(ps) = parents.get(&t) {
                    todo.extend(ps.iter().cloned());
                }
                seen.push(t);
            }
        }
        // One flag per (type, object): bounded by the memory limit, not assumed small (10,000
        // types and a million objects would be 10 GB).
        let cells = (self.c.type_objects.len() as u64).saturating_mul(self.c.objects.len() as u64);
        if !watch.fits(cells) {
            return Err(PlanError::Stopped(Limit::Memory));
        }
        self.rebuild_membership();
        Ok(())
    }

    pub(super) fn rebuild_membership(&mut self) {
        let n = self.c.objects.len();
        self.c.type_member = self
            .c
            .type_objects
            .iter()
            .map(|objs| {
                let mut m = vec![false; n];
                for &o in objs {
                    m[o as usize] = true;
                }
                m
            })
            .collect();
    }

    pub(super) fn ty(&mut self, name: &str) -> u32 {
        let t = self.type_id(name);
        if t as usize >= self.c.type_member.len() {
            self.rebuild_membership();
        }
        t
    }

    pub(super) fn add_task(&mut self, name: &str, action: Option<u32>) {
        if let Some(&t) = self.c.task_ids.get(name) {
            if action.is_some() {
                self.c.tasks[t as usize].action = action;
            }
            return;
        }
        self.c
            .task_ids
            .insert(name.to_string(), self.c.tasks.len() as u32);
        self.c.tasks.push(CTask {
            name: name.to_string(),
            action,
            methods: Vec::new(),
        });
    }

    pub(super) fn pred(&self, name: &str) -> Result<u32, PlanError> {
        self.c
            .pred_ids
            .get(name)
            .copied()
            .ok_or_else(|| PlanError::Model(format!("unknown predicate `{name}`")))
    }

    pub(super) fn object(&self, name: &str) -> Result<u32, PlanError> {
        self.c
            .object_ids
            .get(name)
            .copied()
            .ok_or_else(|| PlanError::Model(format!("unknown object `{name}`")))
    }
}
