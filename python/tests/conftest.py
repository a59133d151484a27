"""Shared fixtures: the repository's library scenario and small HDDL files written per test."""

from pathlib import Path

import pytest

import htngtp

REPO = Path(__file__).resolve().parents[2]
LIBRARY = REPO / "domains" / "library"
SCENE = LIBRARY / "scene.toml"

# A symbolic domain (no geometric tasks): deliver a parcel by driving then dropping it.
DELIVERY_DOMAIN = """(define (domain delivery)
  (:requirements :hierarchy :typing :negative-preconditions)
  (:types place parcel)
  (:predicates (at ?p - place) (parcel-at ?x - parcel ?p - place) (loaded ?x - parcel))
  (:task deliver :parameters (?x - parcel ?to - place))
  (:method m-deliver
    :parameters (?x - parcel ?from ?to - place)
    :task (deliver ?x ?to)
    :precondition (and (at ?from) (parcel-at ?x ?from))
    :ordered-subtasks (and (load ?x ?from) (drive ?from ?to) (unload ?x ?to)))
  (:action load :parameters (?x - parcel ?p - place)
    :precondition (and (at ?p) (parcel-at ?x ?p))
    :effect (and (loaded ?x) (not (parcel-at ?x ?p))))
  (:action drive :parameters (?a ?b - place)
    :precondition (at ?a)
    :effect (and (at ?b) (not (at ?a))))
  (:action unload :parameters (?x - parcel ?p - place)
    :precondition (and (at ?p) (loaded ?x))
    :effect (and (parcel-at ?x ?p) (not (loaded ?x))))
)
"""

DELIVERY_PROBLEM = """(define (problem deliver-one) (:domain delivery)
  (:objects depot shop - place box - parcel)
  (:htn :parameters () :ordered-subtasks (and (deliver box shop)))
  (:init (at depot) (parcel-at box depot)))
"""

# The parcel is nowhere the truck is: no method of `deliver` applies, and the search space is
# finite, so the planner proves that no plan exists.
UNSOLVABLE_PROBLEM = """(define (problem lost-parcel) (:domain delivery)
  (:objects depot shop - place box - parcel)
  (:htn :parameters () :ordered-subtasks (and (deliver box shop)))
  (:init (at depot) (parcel-at box shop)))
"""

# Counting up forever to find a negative count: only a limit stops the search.
COUNTER_DOMAIN = """(define (domain counter)
  (:requirements :hierarchy :numeric-fluents)
  (:functions (count))
  (:task count-up :parameters ())
  (:method found :parameters () :task (count-up) :precondition (< (count) 0)
    :ordered-subtasks ())
  (:method step :parameters () :task (count-up) :ordered-subtasks (and (tick) (count-up)))
  (:action tick :parameters () :effect (increase (count) 1))
)
"""

COUNTER_PROBLEM = """(define (problem counter) (:domain counter)
  (:htn :parameters () :ordered-subtasks (and (count-up)))
  (:init (= (count) 0)))
"""


@pytest.fixture
def hddl(tmp_path):
    """Writes HDDL text into tmp_path and returns the file's path."""

    def write(name: str, text: str) -> Path:
        path = tmp_path / name
        path.write_text(text)
        return path

    return write


@pytest.fixture(scope="session")
def world() -> htngtp.World:
    return htngtp.World.load(SCENE)


@pytest.fixture(scope="session")
def demo_plan() -> htngtp.Plan:
    """The demo's plan (htngtp demo): the compound library domain, Fig. 4's problem, the
    library scene, geometric-first backtracking, seed 1."""
    return htngtp.plan(
        LIBRARY / "domain-compound.hddl",
        LIBRARY / "fig4.hddl",
        scene=SCENE,
        strategy="geometric-first",
        seed=1,
    )
