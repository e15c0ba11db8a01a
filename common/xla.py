"""XLA compiler options shared by the library's programs."""

from __future__ import annotations

# For a program that runs once per job and draws random numbers (a simulation's initial states, a
# network's fresh weights): LLVM's optimisation level 2 instead of XLA's default 3. At level 3 most
# of such a program's compile goes to the random draws (threefry and, for weights, the truncated
# normal's inverse error function); at 2 it compiles several times faster and gives the same
# bits (docs/performance.md, "Compile time", says which programs were checked on which
# instruction sets). A program that runs often (a step, a rollout) keeps the default.
ONCE_PER_RUN = {"xla_backend_optimization_level": 2}
