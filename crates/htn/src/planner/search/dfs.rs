//! The depth-first engine (the SHOP family): the first subtask of the network is expanded,
//! methods in domain order and bindings in the binder's order, with chronological
//! backtracking over the choice points; duplicate nodes, nodes past the depth bound and
//! decompositions that made no progress are pruned.

use super::super::{PlanError, Strategy};
use super::frames::{Choice, HtnFrame, HtnId, Key};
use super::repair::Mode;
use super::{
    Cell, FIRST_CHUNK, MAX_CHUNK, NIL, Search, Step, Stop, TreeRec, bound_terms, set_growth,
};
use crate::planner::eval::Eval;

/// How many ancestors the loop check compares states with (beyond, only ancestors with no
/// action executed since count).
pub(super) const LOOP_WINDOW: usize = 32;

impl<'a, 'o> Search<'a, 'o> {
    /// One depth-first iteration under the current depth bound, from the initial task
    /// network: [`Stop::Found`] with the plan in the state, or why it stopped.
    pub(super) fn dfs(&mut self) -> Result<Stop, PlanError> {
        self.top = NIL;
        if !self.push_htn_frame(NIL, NIL, NIL, NIL)? && !self.fail()? {
            return Ok(Stop::Exhausted);
        }
        loop {
            if let Some(l) = self.check_limits() {
                return Ok(Stop::Limit(l));
            }
            // A handover waits for a repair in progress to end: the repair's state names the
            // frames the next engine's reset pops.
            if let Some(t) = self.switch_at
                && self.mode == Mode::Normal
                && self.start.elapsed() >= t
            {
                return Ok(Stop::Switch);
            }
            if self.run_cap.is_some_and(|cap| self.stats.nodes >= cap) {
                return Ok(Stop::Switch);
            }
            if self.top == NIL {
                if self.goal_holds() {
                    return Ok(Stop::Found);
                }
                if !self.fail()? {
                    return Ok(Stop::Exhausted);
                }
                continue;
            }
            self.stats.nodes += 1;
            let cell = self.arena[self.top as usize];
            let ok = if cell.len as usize > self.bound {
                self.cutoff = true;
                self.stats.depth_cutoffs += 1;
                false
            } else if !self.goal_reachable(cell.may) {
                self.stats.goal_pruned += 1;
                false
            } else if self.mode == Mode::Normal
                && self.opts.duplicate_detection
                && !self.first_visit(cell.hash)
            {
                self.stats.revisits_pruned += 1;
                false
            } else {
                let task = self.gtasks.key(cell.task)[0];
                match self.c.tasks[task as usize].action {
                    Some(a) => self.expand_action(a, cell)?,
                    None => {
                        if self.loop_check && self.no_progress_repeat(cell) {
                            self.stats.loops_pruned += 1;
                            false
                        } else {
                            self.push_htn_frame(cell.task, cell.occ, cell.next, cell.parent)?
                        }
                    }
                }
            };
            if !ok && !self.fail()? {
                return Ok(Stop::Exhausted);
            }
        }
    }

    /// Whether the same ground task is being decomposed by one of its own ancestors in the
    /// same state (recursion that made no progress: whatever was executed since, if anything,
    /// led back to the state the outer occurrence started in, so the inner occurrence can only
    /// repeat what the outer one may do). Ancestors with no action since are all looked at;
    /// with actions since, only the nearest [`LOOP_WINDOW`] (the walk stays cheap in deep
    /// decompositions, and seeing fewer repeats only prunes less).
    pub(super) fn no_progress_repeat(&self, cell: Cell) -> bool {
        let steps = self.steps.len() as u32;
        let mut r = cell.parent;
        let mut now = None;
        let mut dist = 0;
        while r != NIL {
            let rec = &self.tree[r as usize];
            let same_steps = rec.steps == steps;
            if !same_steps && dist >= LOOP_WINDOW {
                return false;
            }
            if rec.task == cell.task {
                if same_steps {
                    return true;
                }
                let now = *now.get_or_insert_with(|| self.state_fingerprint());
                if rec.state == now {
                    return true;
                }
            }
            dist += 1;
            r = rec.parent;
        }
        false
    }

    /// Whether the node (state, geometric world and network `net_hash`) is met for the first
    /// time in this iteration; records it.
    pub(super) fn first_visit(&mut self, net_hash: u64) -> bool {
        if !self.growth_fits(set_growth(&self.visited)) {
            // The table would double past the memory limit: stop (at the next check) rather
            // than grow. Taking the node as new loses nothing, the search ends there.
            return true;
        }
        let h = self.state_fingerprint();
        self.visited.insert(((h as u128) << 64) | net_hash as u128)
    }

    /// A search failure at the current node.
    pub(super) fn fail(&mut self) -> Result<bool, PlanError> {
        match self.mode {
            Mode::Normal => self.backtrack(),
            Mode::Retry => self.next_repair_try(),
            Mode::Restore => {
                // The replay of the original choices did not reproduce them (a back end that
                // is not deterministic): give up the repair and backtrack from here.
                self.end_repair();
                self.backtrack()
            }
        }
    }

    /// Restores frames from the top down until one has an alternative left; `false` when
    /// none has.
    pub(super) fn backtrack(&mut self) -> Result<bool, PlanError> {
        while !self.frames.is_empty() {
            self.restore_top();
            if self.next_alternative()? {
                return Ok(true);
            }
            self.pop_frame();
        }
        Ok(false)
    }

    /// Pushes the choice point of ground task `task` (the initial network when `NIL`) and
    /// takes its first method and binding, or the one a repair replays; on no applicable
    /// method under geometric-first, starts a repair if the geometry may be the cause.
    pub(super) fn push_htn_frame(
        &mut self,
        task: u32,
        occ: u32,
        rest: u32,
        parent: u32,
    ) -> Result<bool, PlanError> {
        if self.mode == Mode::Restore && self.forced.is_empty() && task != NIL {
            // Back at a failure point of a repair with the original choices: fall back to HTN
            // backtracking from here (see `expand_gs`).
            self.end_repair();
            return Ok(false);
        }
        let h = self.push_htn(HtnFrame::new(task, occ, rest, parent));
        if self.mode != Mode::Normal && !self.forced.is_empty() {
            let Some(Key::Htn { method, binding }) = self.forced.pop_front() else {
                return Ok(false);
            };
            let methods = self.methods_of(task);
            let Some(pos) = methods.iter().position(|&m| m == method) else {
                return Ok(false);
            };
            let stride = self.c.methods[method as usize].n_params;
            let mut after = None;
            let (bindings, count, more, idx) = loop {
                let (bindings, count, more) =
                    self.bindings_after(method, task, after.as_ref(), MAX_CHUNK);
                let found = (0..count).find(|&i| bindings[i * stride..(i + 1) * stride] == binding);
                match (found, more) {
                    (Some(idx), more) => break (bindings, count, more, idx),
                    (None, Some(cursor)) => after = Some(cursor),
                    (None, None) => return Ok(false),
                }
            };
            let f = &mut self.htn_frames[h];
            f.mpos = pos + 1;
            f.method = method;
            f.stride = stride;
            f.bindings = bindings;
            f.count = count;
            f.more = more;
            f.next = idx + 1;
            f.tried = 1;
            self.apply_method(h, method, &binding);
            return Ok(true);
        }
        if self.next_alternative()? {
            if self.mode == Mode::Retry && self.forced.is_empty() {
                // The task that had no applicable method has one after the repair.
                self.stats.geo_repairs_succeeded += 1;
                self.end_repair();
            }
            return Ok(true);
        }
        // No method applies, and some method's precondition reads shared literals: the
        // geometry made it fail (Fig. 4: a book placed so that it hides another). With
        // geometric-first, other solutions of earlier geometric tasks come first, as on a
        // failing GS action.
        if self.mode == Mode::Normal
            && task != NIL
            && let Strategy::GeometricFirst { k } = self.opts.strategy
            && k > 0
            && self.methods_read_shared(task)
        {
            self.pop_frame();
            return self.start_repair(k);
        }
        Ok(false)
    }

    /// Tries the top frame's next alternative (the frame is restored).
    pub(super) fn next_alternative(&mut self) -> Result<bool, PlanError> {
        let Some(top) = self.frames.last() else {
            return Ok(false);
        };
        match top.choice {
            Choice::Htn(h) => Ok(self.next_method_alternative(h)),
            Choice::Geo(g) => {
                if self.opts.strategy != Strategy::Chronological || self.geo_frames[g].exhausted {
                    return Ok(false);
                }
                loop {
                    let idx = self.geo_frames[g].current + 1;
                    if self.geo_frames[g].deep {
                        let revisions = self.geo_frames[g].revisions + 1;
                        if !self.within_discrepancy(revisions) {
                            self.discrepancy_cut = true;
                            return Ok(false);
                        }
                        self.geo_frames[g].revisions = revisions;
                    }
                    if !self.fetch(g, idx)? {
                        return Ok(false);
                    }
                    self.stats.geo_backtracks += 1;
                    self.geo_frames[g].current = idx;
                    self.geo_frames[g].deep = false;
                    if self.apply_geo(g)? {
                        return Ok(true);
                    }
                }
            }
        }
    }

    /// Whether the current round of limited discrepancy lets the top geometric frame revise
    /// its solution for the `revisions`-th time (see `GeoFrame::deep`): in round `r`, at most
    /// `r` frames of the path revised, each at most `2^r` times.
    fn within_discrepancy(&self, revisions: u32) -> bool {
        let Some(r) = self.discrepancy else {
            return true;
        };
        // The top frame itself is the one about to be revised (again).
        let others = self.geo_frames.iter().rev().skip(1);
        let revised = others.filter(|f| f.revisions > 0).count();
        revised < r as usize && revisions <= 1u32 << r.min(30)
    }

    /// Takes the next method-and-binding choice of HTN frame `h` (the top frame, restored):
    /// the current method's next binding, else the next method in domain order that has one.
    pub(super) fn next_method_alternative(&mut self, h: HtnId) -> bool {
        loop {
            let f = &mut self.htn_frames[h];
            if f.next < f.count {
                let i = f.next;
                f.next += 1;
                let (m, rest) = (f.method, f.rest);
                let binding = f.binding(i).to_vec();
                if self.consumes_needed(m, &binding, rest) {
                    self.stats.consumed_pruned += 1;
                    continue;
                }
                let f = &mut self.htn_frames[h];
                if f.tried > 0 {
                    self.stats.htn_backtracks += 1;
                }
                f.tried += 1;
                self.apply_method(h, m, &binding);
                return true;
            }
            if let Some(after) = f.more.take() {
                // The current method's next piece of bindings, larger each time.
                let (m, task, max) = (
                    f.method,
                    f.task,
                    (f.count * 4).clamp(FIRST_CHUNK, MAX_CHUNK),
                );
                let (mut bindings, count, more) = self.bindings_after(m, task, Some(&after), max);
                self.order_bindings(&mut bindings, count);
                self.goals_first(m, &mut bindings, count);
                let f = &mut self.htn_frames[h];
                (f.bindings, f.count, f.more, f.next) = (bindings, count, more, 0);
                continue;
            }
            let (task, mpos) = (f.task, f.mpos);
            let methods = self.methods_of(task);
            if mpos >= methods.len() {
                return false;
            }
            let m = methods[self.method_order(task, methods.len(), mpos)];
            let (mut bindings, count, more) = self.bindings_after(m, task, None, FIRST_CHUNK);
            self.order_bindings(&mut bindings, count);
            self.goals_first(m, &mut bindings, count);
            let f = &mut self.htn_frames[h];
            f.mpos = mpos + 1;
            f.method = m;
            f.stride = self.c.methods[m as usize].n_params;
            f.bindings = bindings;
            f.count = count;
            f.more = more;
            f.next = 0;
        }
    }

    /// Decomposes the task of HTN frame `h` (the top frame) with method `m` under `binding`.
    pub(super) fn apply_method(&mut self, h: HtnId, m: u32, binding: &[u32]) {
        let f = &self.htn_frames[h];
        let (occ, task, rest, parent) = (f.occ, f.task, f.rest, f.parent);
        let named = self.bound_task(m, task, binding);
        let method = &self.c.methods[m as usize];
        let first = self.next_occ;
        let n = method.subtasks.len() as u32;
        let rec = self.tree.len() as u32;
        self.tree.push(TreeRec {
            occ,
            task,
            named,
            method: m,
            first,
            n,
            parent,
            steps: self.steps.len() as u32,
            state: self.state_fingerprint(),
        });
        self.next_occ += n;
        let mut top_cell = rest;
        let mut key: Vec<u32> = Vec::with_capacity(8);
        for (i, (t, args)) in method.subtasks.iter().enumerate().rev() {
            key.clear();
            key.push(*t);
            key.extend(bound_terms(args, binding));
            let gt = self.gtasks.intern(&key);
            top_cell = self.push_cell(gt, first + i as u32, top_cell, rec);
        }
        self.top = top_cell;
    }

    /// Applies primitive task `cell` (action `a`) if its precondition holds; GS actions go to
    /// [`Search::expand_gs`].
    pub(super) fn expand_action(&mut self, a: u32, cell: Cell) -> Result<bool, PlanError> {
        let c = self.c;
        let act = &c.actions[a as usize];
        let Some(mut slots) = self.action_slots(a, cell.task) else {
            return Ok(false);
        };
        let ev = Eval {
            c,
            s: &self.state,
            types: &act.slot_types,
        };
        if !ev.all_hold(&act.pre, &mut slots) {
            return Ok(false);
        }
        if act.evaluable.is_some() {
            return self.expand_gs(a, cell, slots);
        }
        self.effects.clear();
        if !ev.effects(&act.effects, &mut slots, &mut self.effects) {
            return Ok(false);
        }
        let mark = self.state.mark();
        self.effects.apply(&mut self.state);
        if self.guards.is_some() && !self.guarded_goals_alive(mark, cell.next) {
            self.stats.goal_pruned += 1;
            return Ok(false);
        }
        self.steps.push(Step {
            occ: cell.occ,
            task: cell.task,
            geo: None,
        });
        self.top = cell.next;
        Ok(true)
    }
}
