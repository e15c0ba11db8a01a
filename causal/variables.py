"""The causal variables of seed 000 and the structure the simulator is built to have.

System variables: V robot speed (m/s), L battery change per sample (%), D people density at
the dataset's waypoint (people/m^2, Eq. 3). Contexts: W waypoint, S time slot, C charging,
O obstacle. Contexts are declared to J-PCMCI+ as space contexts (same-time links only): the
notes in ``shared/notes/causal-stack.md`` found time contexts give false links at large n.
"""

from __future__ import annotations

VARIABLES = ("V", "L", "D", "W", "S", "C", "O")
SYSTEM = ("V", "L", "D")
CONTEXTS = ("W", "S", "C", "O")

# (cause, effect, lag): lag 0 is contemporaneous, lag 1 is cause(t-1) -> effect(t).
GROUND_TRUTH = frozenset(
    {
        ("O", "V", 0),
        ("C", "V", 0),
        ("V", "V", 1),
        ("O", "L", 0),
        ("C", "L", 0),
        ("V", "L", 0),
        ("W", "D", 0),
        ("S", "D", 0),
        ("D", "D", 1),
    }
)


def node_classification(names=VARIABLES) -> dict[int, str]:
    """tigramite's node classification for ``names`` (system or space context)."""
    return {i: "space_context" if n in CONTEXTS else "system" for i, n in enumerate(names)}
