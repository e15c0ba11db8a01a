"""A calibration's ``fit.json`` read back as people a run can walk among.

``socialnav humans calibrate`` writes one record a fit (:func:`evaluation.humans.calibration.calibrate`
for the Jülich corridors, :func:`evaluation.humans.own_recording.calibrate` for a user's recording);
each holds the model it started from and, per method (``gradient``, ``nelder_mead``), the fitted
values and the loss they reached on the fit's training data. This module reads either kind into
:class:`FittedPeople`: the model's name and its constants as ``"<part>.<field>"`` -> value (the
form :func:`jaxsim.humans.with_values` sets), so that the arena (``socialnav arena --human-fit``)
and the validation (``socialnav humans validate --fit``) run the people a user fitted. An ETH/UCY
or a joint fit holds one fit a held-out scene or a weight, not one model: refused.

Which method: ``best`` (the default) takes the one whose training loss is lower, so the choice
reads only what the fit itself read (never the held-out scores the record also holds).
"""

from __future__ import annotations

import dataclasses
import json
import math
import pathlib

from socialnav.evaluation.humans import calibration as hc
from socialnav.jaxsim import humans

METHODS = ("gradient", "nelder_mead")
CHOICES = ("best", *METHODS)
KINDS = ("juelich", "tracks")  # the fits that are one model each


@dataclasses.dataclass(frozen=True)
class FittedPeople:
    """One method's point of a fit.

    Attributes:
      model: the human model the fit started from (:data:`jaxsim.humans.HUMAN_MODELS`; a
        ``_calibrated`` name keeps its preset's constants the fit did not set).
      values: ``"<part>.<field>"`` -> the fitted value (:func:`jaxsim.humans.with_values`).
      method: ``gradient`` or ``nelder_mead``.
      training_loss: the loss it reached on the fit's training data (None where the record has none).
      file: the fit file; data: ``juelich`` or ``tracks``; complete: False for a stopped fit's
        ``progress.json`` (its best point so far).
    """

    model: str
    values: dict
    method: str
    training_loss: float | None
    file: pathlib.Path
    data: str
    complete: bool = True

    @property
    def label(self) -> str:
        """``<folder>:<method>``, the name ``socialnav humans validate`` gives it."""
        return f"{self.file.parent.name}:{self.method}"


def split_option(text: str) -> tuple[pathlib.Path, str]:
    """``FIT_JSON[:METHOD]`` -> the file and the method (``best`` when none is named)."""
    head, _, tail = text.rpartition(":")
    if head and tail in CHOICES:
        return pathlib.Path(head), tail
    return pathlib.Path(text), "best"


def read_points(path, methods=METHODS) -> dict[str, FittedPeople]:
    """The point of each of ``methods`` in the fit file at ``path`` (a stopped fit's
    ``progress.json``: those it has). Raises ``ValueError`` naming the file and the field where
    the file is not a fit of one model."""
    path = pathlib.Path(path)
    try:
        fit = json.loads(path.read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as e:
        raise ValueError(f"{path}: not a readable fit.json ({e})") from None
    if not isinstance(fit, dict):
        raise ValueError(f"{path}: not a fit (expected a JSON object)")
    data = fit.get("data", "juelich")  # a Jülich fit.json written before the field was
    if data not in KINDS:
        raise ValueError(f"{path}: data: a {data!r} fit holds one fit a scene or a weight; only a Jülich fit "
                         "(--data juelich) or one of your recording (--data tracks) is one model")  # fmt: skip
    complete = fit.get("complete", True)  # a fit.json written before the field was: finished
    if not isinstance(complete, bool):
        raise ValueError(f"{path}: complete: {complete!r} is not true or false")
    name = fit.get("model")
    if data == "juelich":
        if name not in hc.FITTED:
            raise ValueError(f"{path}: model: {name!r} is not a model the calibration fits ({', '.join(hc.FITTED)})")
        fields = hc.FITTED[name]
        points = {m: _juelich_point(fit.get(m)) for m in METHODS if m in methods}
    else:
        if not isinstance(name, str) or name not in humans.HUMAN_MODELS:
            raise ValueError(f"{path}: model: {name!r} is not a human model ({', '.join(humans.HUMAN_MODELS)})")
        scenes = fit.get("scenes")
        row = scenes[0] if isinstance(scenes, list) and len(scenes) == 1 and isinstance(scenes[0], dict) else None
        if row is None:
            raise ValueError(f"{path}: scenes: expected one row (the recording's fit)")
        fields = fit.get("fields")
        if not isinstance(fields, list) or not all(isinstance(f, str) for f in fields):
            raise ValueError(f"{path}: fields: expected the list of fitted fields")
        points = {m: _tracks_point(row, m) for m in METHODS if m in methods}
    found = {}
    for method, (values, loss) in points.items():
        if values is None and not complete:
            continue  # the fit stopped before this method found a point
        if values is None:
            raise ValueError(f"{path}: {method}.values: missing")
        wrong = sorted(set(values) ^ set(fields))
        if wrong:
            raise ValueError(f"{path}: {method}.values: expected the fields {', '.join(fields)}, got "
                             f"{', '.join(values)}")  # fmt: skip
        bad = [f for f, v in values.items() if not _positive(v)]
        if bad:
            raise ValueError(f"{path}: {method}.values.{bad[0]}: {values[bad[0]]!r} is not a positive number")
        if data == "juelich":  # its fields are its own part's (the record predates "<part>.<field>")
            values = {f"{humans.PARAMS_OF[name]}.{f}": v for f, v in values.items()}
        problem = humans.values_problem(name, values)
        if problem is not None:
            raise ValueError(f"{path}: {method}.values.{problem}")
        if loss is not None and not (_number(loss) and loss >= 0):
            raise ValueError(f"{path}: {method}: its training loss {loss!r} is not a finite number >= 0")
        found[method] = FittedPeople(name, {k: float(v) for k, v in values.items()}, method,
                                     None if loss is None else float(loss), path, data, complete)  # fmt: skip
    if not found:
        raise ValueError(f"{path}: an unfinished fit with no point yet of {', '.join(methods)}")
    return found


def read_fit(path, method: str = "best") -> FittedPeople:
    """The point of ``method`` in the fit file at ``path``; ``best``: the one of lower training
    loss (the gradient's on a tie; the only one a stopped fit has). Raises ``ValueError`` naming
    the file and the field, or the method the file lacks."""
    if method not in CHOICES:
        raise ValueError(f"method must be one of {', '.join(CHOICES)}, got {method!r}")
    if method != "best":
        return read_points(path, (method,))[method]
    points = read_points(path)
    if len(points) == 1:
        return next(iter(points.values()))
    losses = {m: p.training_loss for m, p in points.items()}
    if any(loss is None for loss in losses.values()):
        missing = [m for m, loss in losses.items() if loss is None]
        raise ValueError(f"{path}: {missing[0]}.loss: missing, so the better method cannot be told; name one "
                         f"({', '.join(METHODS)})")  # fmt: skip
    return min(points.values(), key=lambda p: (p.training_loss, METHODS.index(p.method)))


def read_option(text: str) -> FittedPeople:
    """The commands' ``--human-fit FIT_JSON[:METHOD]`` read (:func:`split_option`,
    :func:`read_fit`); a calibration's folder stands for its ``fit.json`` (or, for a fit stopped
    before its end, its ``progress.json``). ``ValueError`` naming the file and the field."""
    path, method = split_option(text)
    if path.is_dir():
        inside = [path / name for name in ("fit.json", "progress.json") if (path / name).is_file()]
        if not inside:
            raise ValueError(f"{path}: a folder without a fit.json (socialnav humans calibrate --out writes one)")
        path = inside[0]
    if not path.is_file():
        raise ValueError(f"{path}: no such file")
    return read_fit(path, method)


def for_command(human_fit: str | None, human_model: str | None) -> FittedPeople | None:
    """The people of a command's ``--human-fit`` (:func:`read_option`), None without one;
    ``ValueError`` with the command's one line where it cannot be used (given beside
    ``--human-model``, a bad file)."""
    if human_fit is None:
        return None
    if human_model is not None:
        raise ValueError(
            "--human-fit names its own human model (the one its fit started from): leave out --human-model"
        )
    try:
        return read_option(human_fit)
    except ValueError as e:
        raise ValueError(f"--human-fit {e}") from None


def describe(people: FittedPeople) -> str:
    """One line: the model, the file and method, the training loss and the values."""
    loss = "" if people.training_loss is None else f", training loss {people.training_loss:.3g}"
    stopped = "" if people.complete else " (a stopped fit's best point so far)"
    values = ", ".join(f"{k} {v:.4g}" for k, v in people.values.items())
    return f"people by {people.model} as {people.file} fitted them ({people.method}{loss}){stopped}: {values}"


def _juelich_point(entry) -> tuple[dict | None, float | None]:
    if entry is None:
        return None, None
    values = entry.get("values") if isinstance(entry, dict) else None
    return (values, entry.get("loss")) if isinstance(values, dict) else (None, None)


def _tracks_point(row: dict, method: str) -> tuple[dict | None, float | None]:
    values = row.get(f"{method}_values")
    if not isinstance(values, dict):
        return None, None
    losses = row.get("sample_loss")
    return values, losses.get(method) if isinstance(losses, dict) else None


def _number(value) -> bool:
    return not isinstance(value, bool) and isinstance(value, int | float) and math.isfinite(value)


def _positive(value) -> bool:
    return _number(value) and value > 0


__all__ = ["CHOICES", "METHODS", "FittedPeople", "describe", "for_command", "read_fit", "read_option", "read_points",
           "split_option"]  # fmt: skip
