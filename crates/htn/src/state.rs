//! The planner's world state: interned ground facts in a bitset with per-predicate lists, numeric
//! fluent values, an undo trail, and an incrementally maintained Zobrist hash.
//!
//! Everything is a `u32` here: predicates, objects, facts and fluents are interned by the
//! planner's compiler. A fact is `[predicate, arg1, ...]`; interning gives it a dense id so the
//! state is a bitset plus, per predicate, the list of true facts (for binding variables).

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

/// A small, fast, non-cryptographic hasher for integer keys (the FxHash mix).
#[derive(Default, Clone, Copy)]
pub struct FxHasher {
    hash: u64,
}

const FX_K: u64 = 0xf135_7aea_2e62_a9c5;

impl Hasher for FxHasher {
    fn write(&mut self, bytes: &[u8]) {
        let mut chunks = bytes.chunks_exact(8);
        for c in &mut chunks {
            self.write_u64(u64::from_le_bytes(c.try_into().expect("8 bytes")));
        }
        let rest = chunks.remainder();
        if !rest.is_empty() {
            let mut buf = [0u8; 8];
            buf[..rest.len()].copy_from_slice(rest);
            self.write_u64(u64::from_le_bytes(buf));
        }
    }
    fn write_u32(&mut self, i: u32) {
        self.write_u64(i as u64);
    }
    fn write_u64(&mut self, i: u64) {
        self.hash = (self.hash.rotate_left(26) ^ i).wrapping_mul(FX_K);
    }
    fn write_usize(&mut self, i: usize) {
        self.write_u64(i as u64);
    }
    fn finish(&self) -> u64 {
        self.hash.rotate_left(26)
    }
}

/// A `HashMap` with [`FxHasher`].
pub type FxMap<K, V> = HashMap<K, V, BuildHasherDefault<FxHasher>>;

/// SplitMix64: a good 64-bit mixer for Zobrist keys and hash combination.
pub fn mix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// Interns `u32` tuples (facts `[pred, args..]`, ground tasks `[task, args..]`, fluents) to dense ids.
#[derive(Default, Clone)]
pub struct Interner {
    map: FxMap<Box<[u32]>, u32>,
    starts: Vec<u32>,
    data: Vec<u32>,
}

impl Interner {
    /// The id of `key`, if it was interned.
    pub fn get(&self, key: &[u32]) -> Option<u32> {
        self.map.get(key).copied()
    }

    /// The id of `key`, interning it when new.
    pub fn intern(&mut self, key: &[u32]) -> u32 {
        if let Some(&id) = self.map.get(key) {
            return id;
        }
        let id = self.starts.len() as u32;
        self.starts.push(self.data.len() as u32);
        self.data.extend_from_slice(key);
        self.map.insert(key.into(), id);
        id
    }

    /// The tuple of an id.
    pub fn key(&self, id: u32) -> &[u32] {
        let s = self.starts[id as usize] as usize;
        let e = self
            .starts
            .get(id as usize + 1)
            .map_or(self.data.len(), |&e| e as usize);
        &self.data[s..e]
    }

    /// How many tuples are interned.
    pub fn len(&self) -> usize {
        self.starts.len()
    }

    /// Whether nothing is interned.
    pub fn is_empty(&self) -> bool {
        self.starts.is_empty()
    }
}

/// One undoable change of the state.
#[derive(Clone, Copy, Debug)]
enum Change {
    Added(u32),
    Deleted(u32),
    Fluent(u32, f64),
}

/// The symbolic state: which facts hold and the fluent values, with an undo trail.
#[derive(Clone)]
pub struct State {
    /// Fact interning (`[pred, args..]`).
    pub facts: Interner,
    /// Fluent interning (`[function, args..]`).
    pub fluent_keys: Interner,
    bits: Vec<u64>,
    /// Per predicate, the facts that hold now (order changes with adds and deletes).
    by_pred: Vec<Vec<u32>>,
    /// Position of a true fact in its predicate's list.
    pos: Vec<u32>,
    /// Fluent values; NaN is "undefined".
    values: Vec<f64>,
    trail: Vec<Change>,
    hash: u64,
    salt: u64,
    /// Predicates whose facts never change.
    is_static: Vec<bool>,
    /// The facts of static predicates by (predicate, argument position, object).
    static_index: FxMap<(u32, u32, u32), Vec<u32>>,
    /// Per fact, the watched positive / negative literal on it (`u32::MAX`: none).
    watch_pos: Vec<u32>,
    watch_neg: Vec<u32>,
    /// Watched literals that are false now (one bit each).
    unsat: Vec<u64>,
}

impl State {
    /// An empty state over `n_preds` predicates; `salt` seeds the Zobrist keys.
    pub fn new(n_preds: usize, salt: u64) -> State {
        State {
            facts: Interner::default(),
            fluent_keys: Interner::default(),
            bits: Vec::new(),
            by_pred: vec![Vec::new(); n_preds],
            pos: Vec::new(),
            values: Vec::new(),
            trail: Vec::new(),
            hash: 0,
            salt,
            is_static: vec![false; n_preds],
            static_index: FxMap::default(),
            watch_pos: Vec::new(),
            watch_neg: Vec::new(),
            unsat: Vec::new(),
        }
    }

    /// Watches literals (fact key and sign; each at most once): [`State::unsat`] then tells
    /// which are false, kept up to date by every change and undo.
    pub fn watch(&mut self, lits: &[(Vec<u32>, bool)]) {
        self.unsat = vec![0; lits.len().div_ceil(64)];
        for (i, (key, positive)) in lits.iter().enumerate() {
            let id = self.intern_fact(key) as usize;
            if *positive {
                self.watch_pos[id] = i as u32;
            } else {
                self.watch_neg[id] = i as u32;
            }
            if self.holds_id(id as u32) != *positive {
                self.unsat[i / 64] |= 1 << (i % 64);
            }
        }
    }

    /// The watched literals that are false now, as a bitset.
    #[inline]
    pub fn unsat(&self) -> &[u64] {
        &self.unsat
    }

    #[inline]
    fn flip_watch(&mut self, id: u32, now_true: bool) {
        let (p, n) = (self.watch_pos[id as usize], self.watch_neg[id as usize]);
        if p != u32::MAX {
            let (w, b) = (p as usize / 64, p % 64);
            if now_true {
                self.unsat[w] &= !(1 << b);
            } else {
                self.unsat[w] |= 1 << b;
            }
        }
        if n != u32::MAX {
            let (w, b) = (n as usize / 64, n % 64);
            if now_true {
                self.unsat[w] |= 1 << b;
            } else {
                self.unsat[w] &= !(1 << b);
            }
        }
    }

    /// Indexes the facts of the predicates flagged static (call once the initial state is
    /// set; static facts must not change afterwards).
    pub fn index_static(&mut self, is_static: &[bool]) {
        self.is_static = is_static.to_vec();
        self.static_index.clear();
        for (p, facts) in self.by_pred.iter().enumerate() {
            if !is_static.get(p).copied().unwrap_or(false) {
                continue;
            }
            for &f in facts {
                for (k, &o) in self.facts.key(f)[1..].iter().enumerate() {
                    self.static_index
                        .entry((p as u32, k as u32, o))
                        .or_default()
                        .push(f);
                }
            }
        }
    }

    /// Whether `pred` is static (indexed).
    #[inline]
    pub fn is_static(&self, pred: u32) -> bool {
        self.is_static[pred as usize]
    }

    /// The facts of static predicate `pred` whose argument `pos` is `obj`.
    #[inline]
    pub fn static_facts_with(&self, pred: u32, pos: usize, obj: u32) -> &[u32] {
        self.static_index
            .get(&(pred, pos as u32, obj))
            .map_or(&[], Vec::as_slice)
    }

    fn fact_key(&self, f: u32) -> u64 {
        mix64((f as u64) ^ self.salt)
    }

    fn fluent_key(&self, id: u32, v: f64) -> u64 {
        if v.is_nan() {
            return 0;
        }
        mix64(mix64((id as u64) ^ self.salt ^ 0x5555_0000_0000) ^ v.to_bits())
    }

    /// The id of a fact, interning it (does not make it true).
    pub fn intern_fact(&mut self, key: &[u32]) -> u32 {
        let id = self.facts.intern(key);
        if id as usize >= self.pos.len() {
            self.pos.resize(id as usize + 1, u32::MAX);
            self.watch_pos.resize(id as usize + 1, u32::MAX);
            self.watch_neg.resize(id as usize + 1, u32::MAX);
            let words = (id as usize) / 64 + 1;
            if words > self.bits.len() {
                self.bits.resize(words, 0);
            }
        }
        id
    }

    /// Whether fact `id` holds.
    #[inline]
    pub fn holds_id(&self, id: u32) -> bool {
        self.bits
            .get(id as usize / 64)
            .is_some_and(|w| w & (1u64 << (id % 64)) != 0)
    }

    /// Whether the fact `[pred, args..]` holds.
    #[inline]
    pub fn holds(&self, key: &[u32]) -> bool {
        self.facts.get(key).is_some_and(|id| self.holds_id(id))
    }

    /// The facts of predicate `pred` that hold now.
    #[inline]
    pub fn facts_of(&self, pred: u32) -> &[u32] {
        &self.by_pred[pred as usize]
    }

    /// The arguments of fact `id` (without the predicate).
    #[inline]
    pub fn fact_args(&self, id: u32) -> &[u32] {
        &self.facts.key(id)[1..]
    }

    fn set(&mut self, id: u32) {
        let pred = self.facts.key(id)[0] as usize;
        self.bits[id as usize / 64] |= 1u64 << (id % 64);
        self.pos[id as usize] = self.by_pred[pred].len() as u32;
        self.by_pred[pred].push(id);
        self.hash ^= self.fact_key(id);
        self.flip_watch(id, true);
    }

    fn clear(&mut self, id: u32) {
        let pred = self.facts.key(id)[0] as usize;
        self.bits[id as usize / 64] &= !(1u64 << (id % 64));
        let p = self.pos[id as usize] as usize;
        let list = &mut self.by_pred[pred];
        let last = *list.last().expect("a true fact is in its list");
        list.swap_remove(p);
        if last != id {
            self.pos[last as usize] = p as u32;
        }
        self.pos[id as usize] = u32::MAX;
        self.hash ^= self.fact_key(id);
        self.flip_watch(id, false);
    }

    /// Makes fact `id` true, recording the change.
    pub fn add(&mut self, id: u32) {
        if !self.holds_id(id) {
            self.set(id);
            self.trail.push(Change::Added(id));
        }
    }

    /// Makes fact `id` false, recording the change.
    pub fn delete(&mut self, id: u32) {
        if self.holds_id(id) {
            self.clear(id);
            self.trail.push(Change::Deleted(id));
        }
    }

    /// The id of a fluent, interning it (undefined until assigned).
    pub fn intern_fluent(&mut self, key: &[u32]) -> u32 {
        let id = self.fluent_keys.intern(key);
        if id as usize >= self.values.len() {
            self.values.resize(id as usize + 1, f64::NAN);
        }
        id
    }

    /// The value of a fluent; NaN when undefined.
    pub fn value(&self, key: &[u32]) -> f64 {
        self.fluent_keys
            .get(key)
            .map_or(f64::NAN, |id| self.values[id as usize])
    }

    /// Sorts the true facts of `pred` by their keys, so that the order the binder meets them
    /// in does not depend on the history of adds and deletes.
    pub fn sort_facts_of(&mut self, pred: u32) {
        let mut list = std::mem::take(&mut self.by_pred[pred as usize]);
        list.sort_unstable_by(|&a, &b| self.facts.key(a).cmp(self.facts.key(b)));
        for (i, &f) in list.iter().enumerate() {
            self.pos[f as usize] = i as u32;
        }
        self.by_pred[pred as usize] = list;
    }

    /// The fluent values by fluent id (NaN: undefined).
    pub fn values(&self) -> &[f64] {
        &self.values
    }

    /// Sets fluent `id` to `v`, recording the change.
    pub fn set_value(&mut self, id: u32, v: f64) {
        let old = self.values[id as usize];
        if old.to_bits() == v.to_bits() {
            return;
        }
        self.hash ^= self.fluent_key(id, old) ^ self.fluent_key(id, v);
        self.values[id as usize] = v;
        self.trail.push(Change::Fluent(id, old));
    }

    /// The length of the undo trail (a mark to undo back to).
    pub fn mark(&self) -> usize {
        self.trail.len()
    }

    /// Undoes every change made after `mark`.
    pub fn undo_to(&mut self, mark: usize) {
        while self.trail.len() > mark {
            match self.trail.pop().expect("trail longer than mark") {
                Change::Added(id) => self.clear(id),
                Change::Deleted(id) => self.set(id),
                Change::Fluent(id, old) => {
                    let cur = self.values[id as usize];
                    self.hash ^= self.fluent_key(id, cur) ^ self.fluent_key(id, old);
                    self.values[id as usize] = old;
                }
            }
        }
    }

    /// The facts changed since trail mark `mark` (a fact changed twice comes twice).
    pub fn changed_since(&self, mark: usize) -> impl Iterator<Item = u32> + '_ {
        self.trail[mark.min(self.trail.len())..]
            .iter()
            .filter_map(|c| match *c {
                Change::Added(id) | Change::Deleted(id) => Some(id),
                Change::Fluent(..) => None,
            })
    }

    /// The watched literal (index given to [`State::watch`]) that fact `id` makes true, if any.
    #[inline]
    pub fn watched_pos(&self, id: u32) -> Option<u32> {
        self.watch_pos
            .get(id as usize)
            .copied()
            .filter(|&i| i != u32::MAX)
    }

    /// The watched literal that fact `id` makes false, if any.
    #[inline]
    pub fn watched_neg(&self, id: u32) -> Option<u32> {
        self.watch_neg
            .get(id as usize)
            .copied()
            .filter(|&i| i != u32::MAX)
    }

    /// Forgets the trail (after setting up the initial state).
    pub fn commit(&mut self) {
        self.trail.clear();
    }

    /// The Zobrist hash of the facts and fluent values.
    pub fn hash(&self) -> u64 {
        self.hash
    }

    /// All facts that hold, as ids (for the goal and debugging).
    pub fn true_facts(&self) -> impl Iterator<Item = u32> + '_ {
        self.by_pred.iter().flatten().copied()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn add_delete_undo_restore_hash_and_lists() {
        let mut s = State::new(2, 7);
        let a = s.intern_fact(&[0, 1, 2]);
        let b = s.intern_fact(&[0, 3, 4]);
        let c = s.intern_fact(&[1, 5]);
        s.add(a);
        s.add(b);
        s.commit();
        let h0 = s.hash();
        let m = s.mark();
        s.delete(a);
        s.add(c);
        let f = s.intern_fluent(&[0]);
        s.set_value(f, 3.0);
        assert!(!s.holds(&[0, 1, 2]));
        assert!(s.holds(&[1, 5]));
        assert_eq!(s.facts_of(0), &[b]);
        assert_ne!(s.hash(), h0);
        s.undo_to(m);
        assert_eq!(s.hash(), h0);
        assert!(s.holds_id(a) && s.holds_id(b) && !s.holds_id(c));
        assert!(s.value(&[0]).is_nan());
        let mut l = s.facts_of(0).to_vec();
        l.sort();
        assert_eq!(l, vec![a, b]);
    }
}
