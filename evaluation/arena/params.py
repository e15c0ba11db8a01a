"""The arena's parameters from a TOML file: the robot's limits and the layers' and local planners'
parameters, every one a float traced in the episode program (a sweep over files does not
recompile).

A file holds any of these sections, each field optional (the seeds' values are the defaults)::

    [robot]                     # jaxsim.scenes.robot.RobotParams
    max_speed_mps = 0.6
    [casn]                      # planners.layers.casn_layer.CASNParams, for every method with the CASN layer
    personal_radius_m = 1.0
    [snl]                       # planners.layers.snl_layer.SNLParams, for every SNL method
    amplitude = 100.0
    [snape] / [band] / [pursuit]   # SNAPEParams, the social elastic band, pure pursuit
    [methods.snl_large.snl]     # one method only: methods.<method>.<section>
    covariance = 0.7

A method's parameters are its defaults (:func:`planners.stack.layer_params`: the SNL variants
differ in their covariance), then the file's top-level sections, then its ``methods.<name>``
sections. So a top-level ``[snl] covariance`` sets all three SNL variants to one value, and
``[methods.snl_large.snl]`` changes that variant alone. The robot's limits apply to every method
and to ``--actor`` ones (their env). A bad file is refused before any work with one line naming
the file, the section and the field (:class:`ParamsFileError`).
"""

from __future__ import annotations

import dataclasses
import math
import pathlib
import tomllib

from socialnav.jaxsim.scenes.env import EnvConfig
from socialnav.jaxsim.scenes.robot import RobotParams, step_length_problem
from socialnav.planners import stack

# The layer sections: their names are LayerParams' fields.
LAYER_SECTIONS = tuple(f.name for f in dataclasses.fields(stack.LayerParams))


class ParamsFileError(ValueError):
    """A parameter file that cannot be used; the message names the file, section and field."""


@dataclasses.dataclass(frozen=True)
class ArenaParams:
    """The robot's limits, the layers' parameters shared by every method, and per-method ones.

    Attributes:
      robot: the robot's limits (every method, every actor).
      layers: top-level overrides, section -> {field: value}.
      methods: method -> section -> {field: value}.
      text: the file's text ("" for the defaults): what a run's digest and a Ray task carry.
    """

    robot: RobotParams = RobotParams()
    layers: dict = dataclasses.field(default_factory=dict)
    methods: dict = dataclasses.field(default_factory=dict)
    text: str = ""

    def layers_for(self, method: str) -> stack.LayerParams:
        """The :class:`~planners.stack.LayerParams` of a built-in method with this file applied."""
        params = stack.layer_params(stack.METHODS[method])
        for overrides in (self.layers, self.methods.get(method, {})):
            for section, fields in overrides.items():
                params = params.replace(**{section: getattr(params, section).replace(**fields)})
        return params


def _fields(where: str, cls, table) -> dict:
    if not isinstance(table, dict):
        raise ParamsFileError(f"{where}: expected a table of fields, got {type(table).__name__}")
    known = {f.name for f in dataclasses.fields(cls)}
    out = {}
    for name, value in table.items():
        if name not in known:
            raise ParamsFileError(f"{where} {name}: unknown field (known: {', '.join(sorted(known))})")
        if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
            raise ParamsFileError(f"{where} {name}: expected a finite number, got {value!r}")
        if value < 0:
            raise ParamsFileError(f"{where} {name}: must be >= 0, got {value!r}")
        out[name] = float(value)
    return out


def parse(text: str, source: str = "<params>") -> ArenaParams:
    """:class:`ArenaParams` from a TOML text (``source`` names it in errors)."""
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise ParamsFileError(f"{source}: not TOML: {e}") from None
    defaults = stack.LayerParams()
    sections = ("robot", *LAYER_SECTIONS, "methods")
    robot, layers, methods = RobotParams(), {}, {}
    for section, table in data.items():
        where = f"{source}: [{section}]"
        if section == "robot":
            robot = RobotParams(**_fields(where, RobotParams, table))
        elif section in LAYER_SECTIONS:
            layers[section] = _fields(where, type(getattr(defaults, section)), table)
        elif section == "methods":
            if not isinstance(table, dict):
                raise ParamsFileError(f"{where}: expected [methods.<method>.<section>] tables")
            for method, per_method in table.items():
                if method not in stack.METHODS:
                    raise ParamsFileError(
                        f"{source}: [methods.{method}]: unknown method (known: {', '.join(stack.METHODS)})"
                    )
                if not isinstance(per_method, dict):
                    raise ParamsFileError(f"{source}: [methods.{method}]: expected [methods.{method}.<section>]")
                methods[method] = {}
                for sub, fields in per_method.items():
                    if sub not in LAYER_SECTIONS:
                        raise ParamsFileError(
                            f"{source}: [methods.{method}.{sub}]: unknown section (known: {', '.join(LAYER_SECTIONS)})"
                        )
                    methods[method][sub] = _fields(
                        f"{source}: [methods.{method}.{sub}]", type(getattr(defaults, sub)), fields
                    )
        else:
            raise ParamsFileError(f"{where}: unknown section (known: {', '.join(sections)})")
    if robot.radius_m <= 0 or robot.max_speed_mps <= 0:
        raise ParamsFileError(f"{source}: [robot]: radius_m and max_speed_mps must be > 0")
    too_far = step_length_problem(robot, EnvConfig.dt_s)  # the arena steps at the env's default
    if too_far is not None:
        raise ParamsFileError(f"{source}: [robot]: {too_far}")
    return ArenaParams(robot=robot, layers=layers, methods=methods, text=text)


def load(path: str | pathlib.Path) -> ArenaParams:
    """:class:`ArenaParams` of a TOML file (:class:`ParamsFileError` naming the file if unreadable)."""
    path = pathlib.Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as e:
        raise ParamsFileError(f"{path}: cannot read it ({e})") from None
    return parse(text, str(path))
