//! GS actions: their solutions come from the geometric oracle, one stream per action
//! occurrence, fetched lazily and cached on the action's choice point; applying one adds and
//! deletes its shared literals.

use super::super::compile::CTerm;
use super::super::eval::Eval;
use super::super::{PlanError, Strategy};
use super::frames::{GeoFrame, GeoId, Key};
use super::repair::Mode;
use super::{Cell, Search, Step, atom_key};
use crate::plan::GeoStep;

impl<'a, 'o> Search<'a, 'o> {
    /// Opens the oracle's stream for GS action `a` on `cell` (slots bound) as a new choice
    /// point and applies its first solution (or the one a repair replays); on a geometric
    /// failure under geometric-first, starts a repair.
    pub(super) fn expand_gs(
        &mut self,
        a: u32,
        cell: Cell,
        slots: Vec<u32>,
    ) -> Result<bool, PlanError> {
        if self.mode == Mode::Restore && self.forced.is_empty() {
            // Back at the failure point with the original choices: fall back to HTN
            // backtracking from here.
            self.end_repair();
            return Ok(false);
        }
        let c = self.c;
        let (g, args) = c.actions[a as usize]
            .evaluable
            .as_ref()
            .expect("a GS action");
        let names: Vec<String> = args
            .iter()
            .map(|t| {
                let o = match *t {
                    CTerm::Var(v) => slots[v as usize],
                    CTerm::Obj(o) => o,
                };
                c.objects[o as usize].clone()
            })
            .collect();
        let oracle = self
            .oracle
            .as_deref_mut()
            .expect("GS actions need an oracle");
        let stream = oracle.open(&c.geo_tasks[*g as usize], &names)?;
        self.geo_capped |= self.opts.strategy != Strategy::Chronological;
        let top = self.push_geo(GeoFrame {
            occ: cell.occ,
            task: cell.task,
            rest: cell.next,
            action: a,
            slots,
            stream,
            cache: Vec::new(),
            current: 0,
            applied: false,
            exhausted: false,
            deep: false,
            revisions: 0,
        });
        let replaying = self.mode != Mode::Normal && !self.forced.is_empty();
        let want = if replaying {
            match self.forced.pop_front() {
                Some(Key::Geo(j)) if self.mode == Mode::Restore => j,
                Some(Key::Geo(_)) => 0,
                _ => return Ok(false),
            }
        } else {
            0
        };
        if self.fetch(top, want)? {
            self.geo_frames[top].current = want;
            if self.apply_geo(top)? {
                if self.mode == Mode::Retry && self.forced.is_empty() {
                    // The failed geometric task has a solution after the repair.
                    self.stats.geo_repairs_succeeded += 1;
                    self.end_repair();
                }
                return Ok(true);
            }
        }
        // A geometric failure.
        if self.mode == Mode::Normal
            && let Strategy::GeometricFirst { k } = self.opts.strategy
            && k > 0
        {
            self.pop_frame();
            return self.start_repair(k);
        }
        Ok(false)
    }

    /// Makes solution `idx` of geo frame `g` available in its cache; `false` if the stream
    /// has fewer solutions.
    pub(super) fn fetch(&mut self, g: GeoId, idx: usize) -> Result<bool, PlanError> {
        loop {
            let g = &mut self.geo_frames[g];
            if idx < g.cache.len() {
                return Ok(true);
            }
            if g.exhausted || (self.opts.strategy == Strategy::Symbolic && !g.cache.is_empty()) {
                return Ok(false);
            }
            let oracle = self
                .oracle
                .as_deref_mut()
                .expect("GS actions need an oracle");
            match oracle.next_solution(g.stream)? {
                Some(s) => g.cache.push(s),
                None => {
                    g.exhausted = true;
                    return Ok(false);
                }
            }
        }
    }

    /// Takes the current solution of geo frame `g` (the top frame, restored).
    pub(super) fn apply_geo(&mut self, id: GeoId) -> Result<bool, PlanError> {
        let c = self.c;
        let g = &mut self.geo_frames[id];
        let act = &c.actions[g.action as usize];
        let ev = Eval {
            c,
            s: &self.state,
            types: &act.slot_types,
        };
        self.effects.clear();
        if !ev.effects(&act.effects, &mut g.slots, &mut self.effects) {
            return Ok(false);
        }
        self.effects.apply(&mut self.state);
        let sol = &g.cache[g.current];
        for atom in &sol.delete {
            let key = atom_key(c, &atom.predicate, &atom.args)?;
            if let Some(id) = self.state.facts.get(&key) {
                self.state.delete(id);
            }
        }
        for atom in &sol.add {
            let key = atom_key(c, &atom.predicate, &atom.args)?;
            let id = self.state.intern_fact(&key);
            self.state.add(id);
        }
        let oracle = self
            .oracle
            .as_deref_mut()
            .expect("GS actions need an oracle");
        oracle.apply(sol.id)?;
        g.applied = true;
        let (gt, gargs) = act.evaluable.as_ref().expect("a GS action");
        let geo = GeoStep {
            task: c.geo_tasks[*gt as usize].clone(),
            args: gargs
                .iter()
                .map(|t| match *t {
                    CTerm::Var(v) => c.objects[g.slots[v as usize] as usize].clone(),
                    CTerm::Obj(o) => c.objects[o as usize].clone(),
                })
                .collect(),
            add: sol.add.clone(),
            delete: sol.delete.clone(),
            solution: sol.id,
        };
        self.steps.push(Step {
            occ: g.occ,
            task: g.task,
            geo: Some(geo),
        });
        self.top = g.rest;
        // The geometric task before this one now has a solution built on it.
        if let Some(below) = self.geo_frames.below_mut(id) {
            below.deep = true;
        }
        Ok(true)
    }
}
