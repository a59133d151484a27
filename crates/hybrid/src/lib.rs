//! HTN <-> GTP coupling: evaluable predicates answered by the geometric task planner, shared
//! literals as add and delete lists, interleaved backtracking.
