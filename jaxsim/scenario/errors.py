"""The one error a scenario loader raises."""

from __future__ import annotations

import pathlib


class ScenarioError(ValueError):
    """A scenario file is missing, malformed or inconsistent.

    Attributes:
      file: the file at fault.
      field: the JSON field at fault (dotted path).
      reason: what is wrong with it, in words (the message without the file and the field).
    """

    def __init__(self, file: pathlib.Path | str, field: str, message: str):
        self.file = pathlib.Path(file)
        self.field = field
        self.reason = message
        super().__init__(f"{self.file}: field '{field}': {message}")
