//! The lifted HTN domain and problem, as written in HDDL.
//!
//! This is what the parser produces and what the planner and the validator consume. Names are
//! stored lower-cased (HDDL names are case-insensitive), and [`Spellings`] keep how the file
//! spelled each declaration, for output (the competition's verifier matches names exactly);
//! every item keeps the [`Span`] where it
//! was written so later stages can report errors at file:line:column. Subtask lists are always
//! stored in their single total order, whatever spelling the file used.
//!
//! Beyond plain HDDL the model carries numeric fluents (PDDL 2.1 style) and the geometric
//! extension: *shared predicates*, whose facts come from geometry and never from the problem
//! file, and *geometric tasks*, which an action's precondition can ask about through an
//! *evaluable predicate* (see [`Formula::Evaluable`]).

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::sync::Arc;

/// A position in a source file (1-based line and column).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Span {
    pub line: u32,
    pub col: u32,
}

/// The file a model came from, shared by everything parsed from it.
pub type SourceName = Arc<PathBuf>;

/// The root type every object has, whether declared or not.
pub const OBJECT_TYPE: &str = "object";

/// The declared spelling of names of one namespace: case-folded name to the spelling of its
/// first declaration (`achievecontainsshotcocktail` to `AchieveContainsShotCocktail`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Spelling(BTreeMap<String, String>);

impl Spelling {
    /// Records `raw` as the spelling of its case-folded name, unless one is recorded already.
    pub fn declare(&mut self, raw: &str) {
        self.0
            .entry(raw.to_ascii_lowercase())
            .or_insert_with(|| raw.to_string());
    }

    /// The declared spelling of the case-folded `name`; `name` itself when none was recorded.
    pub fn of<'a>(&'a self, name: &'a str) -> &'a str {
        self.0.get(name).map_or(name, String::as_str)
    }

    /// The declared spelling of `name` whatever its case, if it is declared at all.
    pub fn declared(&self, name: &str) -> Option<&str> {
        self.0.get(&name.to_ascii_lowercase()).map(String::as_str)
    }

    /// Adds every spelling of `other` not recorded here.
    pub fn extend(&mut self, other: &Spelling) {
        for (k, v) in &other.0 {
            self.0.entry(k.clone()).or_insert_with(|| v.clone());
        }
    }
}

/// How a file spells its declarations, one table per namespace (a method may share its name
/// with a task, spelled differently).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Spellings {
    /// Types.
    pub types: Spelling,
    /// Constants and objects.
    pub objects: Spelling,
    /// Predicates, shared predicates and functions.
    pub predicates: Spelling,
    /// Abstract tasks and actions (one namespace in HDDL).
    pub tasks: Spelling,
    pub methods: Spelling,
}

/// A name with a type, as in a parameter list or an object list: `?b - book`.
#[derive(Clone, Debug, PartialEq)]
pub struct TypedName {
    /// The name, lower-cased. Variables keep their leading `?`.
    pub name: String,
    /// The declared type, lower-cased; [`OBJECT_TYPE`] when none was given.
    pub ty: String,
    pub span: Span,
}

/// A declared type and its direct parents (a type may be declared with several parents on
/// separate lines of `:types`).
#[derive(Clone, Debug, PartialEq)]
pub struct TypeDecl {
    pub name: String,
    pub parents: Vec<String>,
    pub span: Span,
}

/// A predicate, function, task or geometric task signature: a name and typed parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct Signature {
    pub name: String,
    pub params: Vec<TypedName>,
    pub span: Span,
}

/// An argument of an atom or task: a variable (`?x`) or a constant / object name.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub enum Term {
    /// A variable, stored with its leading `?`.
    Var(String),
    /// A constant or object name.
    Const(String),
}

/// A predicate applied to terms: `(held ?b ?m)`.
#[derive(Clone, Debug, PartialEq)]
pub struct Atom {
    pub predicate: String,
    pub args: Vec<Term>,
    pub span: Span,
}

/// A numeric fluent applied to terms: `(credit ?m)`.
#[derive(Clone, Debug, PartialEq)]
pub struct FluentTerm {
    pub function: String,
    pub args: Vec<Term>,
    pub span: Span,
}

/// Arithmetic operators of numeric expressions.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ArithOp {
    Add,
    Sub,
    Mul,
    Div,
}

impl ArithOp {
    /// `a op b`: the one arithmetic of numeric fluents, for the planner and the validator.
    /// `None` for a division by zero: the value is undefined, as an undefined fluent's is.
    pub fn apply(self, a: f64, b: f64) -> Option<f64> {
        match self {
            ArithOp::Add => Some(a + b),
            ArithOp::Sub => Some(a - b),
            ArithOp::Mul => Some(a * b),
            ArithOp::Div => (b != 0.0).then(|| a / b),
        }
    }
}

/// A numeric expression (PDDL 2.1).
#[derive(Clone, Debug, PartialEq)]
pub enum NumExpr {
    Number(f64),
    Fluent(FluentTerm),
    Binary(ArithOp, Box<NumExpr>, Box<NumExpr>),
    /// Unary minus: `(- e)`.
    Neg(Box<NumExpr>),
}

/// Comparison operators of numeric conditions.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CompareOp {
    Lt,
    Le,
    Eq,
    Ge,
    Gt,
}

/// A precondition, method precondition, constraint or goal.
#[derive(Clone, Debug, PartialEq, Default)]
pub enum Formula {
    /// The empty conjunction `()` or `(and)`.
    #[default]
    True,
    Atom(Atom),
    /// `(= ?a ?b)` between objects.
    Equal(Term, Term, Span),
    Not(Box<Formula>),
    And(Vec<Formula>),
    Or(Vec<Formula>),
    Imply(Box<Formula>, Box<Formula>),
    Exists(Vec<TypedName>, Box<Formula>),
    Forall(Vec<TypedName>, Box<Formula>),
    /// A numeric comparison: `(< (credit ?m) (* (lent ?m) 3))`.
    Compare(CompareOp, NumExpr, NumExpr, Span),
    /// An evaluable predicate `t?` of the paper: true iff the geometric task `t(args)` has a
    /// solution in the current world. Written `(evaluable (make-accessible ?b ?m))`. Allowed
    /// only positively in the top-level conjunction of an action's precondition; each solution
    /// is a choice point, and its add and delete lists of shared literals are applied after the
    /// action's own effects.
    Evaluable {
        task: String,
        args: Vec<Term>,
        span: Span,
    },
}

/// Numeric effect operators.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NumericEffectOp {
    Assign,
    Increase,
    Decrease,
    ScaleUp,
    ScaleDown,
}

impl NumericEffectOp {
    /// A fluent's new value from its current one and the effect's operand `x`. `None` for a
    /// scale-down by zero. (An undefined current value is the caller's to refuse: only
    /// `Assign` may set a fluent that has no value.)
    pub fn apply(self, current: f64, x: f64) -> Option<f64> {
        match self {
            NumericEffectOp::Assign => Some(x),
            NumericEffectOp::Increase => Some(current + x),
            NumericEffectOp::Decrease => Some(current - x),
            NumericEffectOp::ScaleUp => Some(current * x),
            NumericEffectOp::ScaleDown => (x != 0.0).then(|| current / x),
        }
    }
}

/// One effect of an action.
#[derive(Clone, Debug, PartialEq)]
pub enum Effect {
    Add(Atom),
    Delete(Atom),
    /// `(forall (?x - t) effect)`.
    Forall(Vec<TypedName>, Vec<Effect>),
    /// `(when condition effect)`.
    When(Formula, Vec<Effect>),
    /// `(increase (f ?a) expr)` and its siblings.
    Numeric(NumericEffectOp, FluentTerm, NumExpr),
}

/// A task occurrence in a method body or the initial task network.
#[derive(Clone, Debug, PartialEq)]
pub struct Subtask {
    /// The label used by `:ordering` (`task0`), when one was given.
    pub id: Option<String>,
    /// The task or action name.
    pub name: String,
    pub args: Vec<Term>,
    pub span: Span,
}

/// A primitive action (operator).
#[derive(Clone, Debug, PartialEq)]
pub struct Action {
    pub name: String,
    pub params: Vec<TypedName>,
    pub precondition: Formula,
    pub effects: Vec<Effect>,
    pub span: Span,
}

/// A decomposition method for an abstract task.
#[derive(Clone, Debug, PartialEq)]
pub struct Method {
    pub name: String,
    pub params: Vec<TypedName>,
    /// The abstract task this method decomposes, with its arguments (terms over `params`).
    pub task: String,
    pub task_args: Vec<Term>,
    pub precondition: Formula,
    /// `:constraints` (Monroe); semantically part of the precondition.
    pub constraints: Formula,
    /// The subtasks in their one total order.
    pub subtasks: Vec<Subtask>,
    pub span: Span,
}

/// An HDDL domain with numeric fluents and the geometric extension.
#[derive(Clone, Debug, PartialEq)]
pub struct Domain {
    pub name: String,
    /// The file it was read from, for error messages.
    pub source: SourceName,
    pub requirements: Vec<String>,
    pub types: Vec<TypeDecl>,
    pub constants: Vec<TypedName>,
    /// Ordinary predicates (`:predicates`).
    pub predicates: Vec<Signature>,
    /// Shared predicates (`:shared-predicates`): facts derived from geometry.
    pub shared_predicates: Vec<Signature>,
    /// Numeric fluents (`:functions`).
    pub functions: Vec<Signature>,
    /// Abstract tasks (`:task`).
    pub tasks: Vec<Signature>,
    /// Geometric tasks (`:geometric-tasks`), the targets of evaluable predicates.
    pub geometric_tasks: Vec<Signature>,
    /// Methods in domain order (the order encodes preference).
    pub methods: Vec<Method>,
    pub actions: Vec<Action>,
    /// How the file spells its declared names.
    pub spelling: Spellings,
    /// What the file does that HDDL allows only by custom, each at its place (an undeclared
    /// parent type, taken as a subtype of `object`). The binary prints them as warnings.
    pub warnings: Vec<crate::parser::ParseError>,
}

/// A ground fact of the initial state.
#[derive(Clone, Debug, PartialEq)]
pub struct InitFact {
    pub predicate: String,
    pub args: Vec<String>,
    pub span: Span,
}

/// An initial numeric value: `(= (credit alice) 20)`.
#[derive(Clone, Debug, PartialEq)]
pub struct InitValue {
    pub function: String,
    pub args: Vec<String>,
    pub value: f64,
    pub span: Span,
}

/// The initial task network (`:htn`) of a problem.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct TaskNetwork {
    /// `:parameters` of the network (rare; existentially bound).
    pub params: Vec<TypedName>,
    /// The tasks in their one total order.
    pub subtasks: Vec<Subtask>,
    pub constraints: Formula,
}

/// An HDDL problem.
#[derive(Clone, Debug, PartialEq)]
pub struct Problem {
    pub name: String,
    pub domain_name: String,
    pub source: SourceName,
    pub objects: Vec<TypedName>,
    pub init: Vec<InitFact>,
    pub init_values: Vec<InitValue>,
    pub htn: TaskNetwork,
    /// `:goal`, checked on the final state when present.
    pub goal: Formula,
    /// How the file spells its objects (the other namespaces stay empty).
    pub spelling: Spellings,
}

#[cfg(test)]
mod arithmetic_tests {
    use super::{ArithOp, NumericEffectOp};

    #[test]
    fn division_and_scale_down_by_zero_are_undefined() {
        assert_eq!(ArithOp::Div.apply(6.0, 3.0), Some(2.0));
        assert_eq!(ArithOp::Div.apply(6.0, 0.0), None);
        assert_eq!(NumericEffectOp::ScaleDown.apply(6.0, 0.0), None);
        assert_eq!(NumericEffectOp::Decrease.apply(6.0, 2.0), Some(4.0));
        // Assigning needs no current value.
        assert_eq!(NumericEffectOp::Assign.apply(f64::NAN, 1.0), Some(1.0));
    }
}
