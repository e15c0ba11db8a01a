"""The warehouse simulator's own causal graph, read from its code: the referee of discovery.

Seed 000's pipeline discovers a graph over V (robot speed), L (battery change), D (density at a
waypoint), W (the waypoint), S (the slot), C (charging) and O (obstacle), and scores it against
the paper's Fig. 8 (:data:`causal.variables.GROUND_TRUTH`). The simulator that makes the data has
a structure of its own, written in ``jaxsim``; :data:`EDGES` writes it down, one edge per
dependency of one variable's update on another, at the simulator's step (0.1 s), with the file
and function and the reason. B, the battery level, is in it too: the pipeline does not extract
it, and several of the others' dependencies run through it.

Time within one step (``jaxsim.step.step``): the workers move first, seeing the robot's state
before the step; then ``jaxsim.robot.drive`` computes, in this order, C_t and O_t from the
robot's mode and leg before the step, V_t, L_t = f(V_t, C_t, O_t), B_t = B_{t-1} + L_t; then
``jaxsim.robot.update_robot`` changes the mode (legs, the charger) for the next step. A lag-0
edge is inside that order; a lag-1 edge reads the state the previous step left.

Two edges are summaries of dependencies on quantities the pipeline does not have: the robot
slows for the workers in its lane (``D(t-1) -> V``: D counts those same workers when the robot
is within the waypoint's radius) and the workers avoid the robot (``V(t-1) -> D``: its velocity
and the position it drove to enter their social force). C and O are both read from the robot's
mode (latent): charging rules an obstacle out, written ``C -> O``.

``tests/test_simulator_graph.py`` referees this file against the simulator: in a batch of worlds
a do() on C, O, V or B moves, one and two steps later, only what the graph says it can reach,
and moves each of its same-step children in some world.
"""

from __future__ import annotations

import dataclasses

from socialnav.causal.variables import SYSTEM

NODES = ("V", "L", "B", "C", "O", "D", "W", "S")
STEP_S = 0.1  # the warehouse simulator's step (data/warehouse/params.json dt_s; tested equal)
LATENT = ("B",)  # in the simulator's graph, not extracted by the pipeline


@dataclasses.dataclass(frozen=True)
class Edge:
    """``cause(t - lag) -> effect(t)`` at the simulator's step, where the code makes it."""

    cause: str
    effect: str
    lag: int
    where: str
    why: str


EDGES: tuple[Edge, ...] = (
    # Within a step (jaxsim/robot.py drive; jaxsim/battery.py).
    Edge("C", "V", 0, "jaxsim/robot.py:drive", "a charging robot does not move (v_des = 0 unless moving)"),
    Edge("O", "V", 0, "jaxsim/robot.py:drive", "inside an obstacle the speed is scaled by its drawn factor"),
    Edge("V", "L", 0, "jaxsim/battery.py:battery_change_pct", "Eq. (1): discharge K_s + K_d V"),
    Edge("C", "L", 0, "jaxsim/battery.py:battery_change_pct", "Eq. (1): +K_c while charging"),
    Edge("O", "L", 0, "jaxsim/battery.py:battery_change_pct", "Eq. (1): x K_o with an obstacle"),
    Edge("L", "B", 0, "jaxsim/battery.py:next_battery_pct", "Eq. (2): B_t = B_{t-1} + L_t"),
    Edge("C", "O", 0, "jaxsim/robot.py:drive", "an obstacle is met only on a task leg, never while charging"),
    Edge("W", "D", 0, "jaxsim/step.py:measure", "D is the density inside waypoint W's circle"),
    Edge(
        "S",
        "D",
        0,
        "jaxsim/workers.py:update_context",
        "the slot's destination probabilities and working hours move the workers",
    ),
    # From the previous step's state.
    Edge("V", "V", 1, "jaxsim/robot.py:drive", "the acceleration limit: V_t <= V_{t-1} + a dt"),
    Edge("B", "B", 1, "jaxsim/battery.py:next_battery_pct", "Eq. (2)"),
    Edge("B", "V", 1, "jaxsim/robot.py:drive", "an empty battery stops the robot"),
    Edge(
        "B",
        "C",
        1,
        "jaxsim/robot.py:update_robot",
        "below the recharge level a finished leg sends the robot to the charger; full ends charging",
    ),
    Edge("C", "C", 1, "jaxsim/robot.py:update_robot", "the charging mode lasts until the battery is full"),
    Edge("O", "O", 1, "jaxsim/robot.py:drive", "an obstacle lasts for obstacle_length_m of travel"),
    Edge("V", "O", 1, "jaxsim/robot.py:drive", "the obstacle begins and ends at distances travelled on the leg"),
    Edge("V", "C", 1, "jaxsim/robot.py:update_robot", "arriving at the charger (by travel) starts charging"),
    Edge("D", "D", 1, "jaxsim/crowd.py:step_crowd", "the workers' positions carry over (social force)"),
    Edge(
        "V",
        "D",
        1,
        "jaxsim/workers.py:move",
        "the workers avoid the robot: its velocity and position enter their social force",
    ),
    Edge(
        "D",
        "V",
        1,
        "jaxsim/robot.py:crowd_speed_factor",
        "the robot slows for workers in its lane, the workers D counts when it is at the waypoint",
    ),
    Edge("S", "S", 1, "jaxsim/step.py:current_slot", "the clock"),
    Edge(
        "S",
        "V",
        1,
        "jaxsim/robot.py:start_leg",
        "the slot's task list picks the next goal, so the heading and the workers in the lane",
    ),
    Edge("S", "O", 1, "jaxsim/robot.py:start_leg", "the next goal's planned length places the leg's obstacle"),
)


def as_set(edges=EDGES) -> set[tuple[str, str, int]]:
    """``{(cause, effect, lag)}`` at the simulator's step."""
    return {(e.cause, e.effect, e.lag) for e in edges}


def reachable(start: str, steps: int, edges=EDGES) -> list[set[str]]:
    """What a do() on ``start`` at step t can move at steps t, t + 1, ..., t + ``steps``: the
    nodes reached along edges whose lags add up to each offset (``start`` itself at t)."""
    same = {}
    for e in edges:
        if e.lag == 0:
            same.setdefault(e.cause, set()).add(e.effect)

    def close(nodes: set[str]) -> set[str]:
        out, todo = set(nodes), list(nodes)
        while todo:
            for child in same.get(todo.pop(), ()):
                if child not in out:
                    out.add(child)
                    todo.append(child)
        return out

    levels = [close({start})]
    for _ in range(steps):
        nxt = {e.effect for e in edges if e.lag == 1 and e.cause in levels[-1]}
        # A do() held for one step: what it moved keeps moving what follows; persistence
        # (X -> X at lag 1) is one of those edges.
        levels.append(close(nxt))
    return levels


def pipeline_truth(sampling_steps: int = 1, edges=EDGES, latent=LATENT) -> frozenset[tuple[str, str, int]]:
    """The graph over the pipeline's variables, lags in samples of ``sampling_steps`` simulator
    steps, for :func:`causal.discover.score` (``truth=``).

    A latent node is projected out first: ``X -> B -> Y`` becomes ``X -> Y`` at the sum of the
    lags (``L -> B -> C``: the battery level is the sum of L, so L's history drives charging).
    Then the lags: a variable's dependence on its own past stays at one sample (its memory);
    any other edge of step lag ``l`` lands at sample lag ``l // sampling_steps`` (it acts within
    one sampling period when ``l`` is shorter: at the pipeline's periods of 1 s and more every
    one-step edge is contemporaneous). This project's reading of "the same graph, sampled", and
    a parameter: at ``sampling_steps = 1`` it is the step graph itself.

    Sampled, the graph has same-time feedback (V and O, V and C, C and L, V and D each cause
    the other within a period): outside the acyclic graphs J-PCMCI+ assumes, where a found
    same-time link in either direction counts as right (:func:`causal.discover.score` keeps one
    orientation per same-time pair; both are listed here).
    """
    if sampling_steps < 1:
        raise ValueError(f"sampling_steps must be >= 1, got {sampling_steps}")
    projected = [(e.cause, e.effect, e.lag) for e in edges if e.cause not in latent and e.effect not in latent]
    for b in latent:
        into = [e for e in edges if e.effect == b and e.cause != b]
        out_of = [e for e in edges if e.cause == b and e.effect != b]
        projected += [(i.cause, o.effect, i.lag + o.lag) for i in into for o in out_of]
    out = set()
    for cause, effect, lag in projected:
        out.add((cause, effect, 1 if cause == effect else lag // sampling_steps))
    return frozenset(out)


def findable(truth, system=SYSTEM) -> frozenset[tuple[str, str, int]]:
    """The part of ``truth`` J-PCMCI+ can return with the pipeline's declarations: contexts (W,
    S, C, O) are exogenous space contexts there, so an edge into a context, or a lagged edge out
    of one, is never tested."""
    return frozenset((c, e, lag) for c, e, lag in truth if e in system and (c in system or lag == 0))


def sampling_steps(period_s: float) -> int:
    """Simulator steps per sample of a dataset subsampled to ``period_s``."""
    return max(1, round(period_s / STEP_S))
