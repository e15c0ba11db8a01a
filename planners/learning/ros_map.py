"""A ROS ``map_server`` map (a YAML file and its image) as an occupancy grid of walls.

The format every ROS and Nav2 user has (``nav2_map_server``'s ``map_io``): a YAML file with

* ``image``: the PGM, PNG or BMP file, relative to the YAML's folder or absolute;
* ``resolution``: metres per pixel;
* ``origin``: ``[x, y, yaw]`` of the image's lower-left pixel (yaw must be 0 here: a rotated map is
  refused, not turned);
* ``negate`` (0 or 1, ``true`` or ``false``), ``occupied_thresh`` and ``free_thresh`` (in [0, 1],
  free below occupied), ``mode`` (``trinary``, ``scale`` or ``raw``).

Nav2 requires ``negate`` and both thresholds; here they default to what ``map_saver`` writes (0,
0.65 and 0.25), so a hand-written map of the three required fields reads. Numbers may be written
as YAML reads them or as quoted text (``"0.05"``, ``5e-2``: yaml-cpp, which Nav2 uses, reads both;
PyYAML reads ``5e-2`` as text).

**Which pixels are walls.** A cell is a wall where Nav2's map server would publish 100 (occupied)
and its static costmap layer, with its defaults (``lethal_cost_threshold`` 100), would make the cell
lethal; every other cell, unknown ones included, is free (the GSCL network's input has walls and
free cells only, as a static layer with ``track_unknown_space`` false has). Per pixel, as
``map_io.cpp`` computes it: the shade is the mean of the red, green and blue channels in [0, 1]
(grey images: the grey level; 16-bit images: over 65535), and in ``trinary`` mode an image with
an alpha channel averages its opacity in as a fourth channel (a PNG with a ``tRNS`` chunk, grey or
palette, has one, as Nav2's image library reads it); ``occ`` is ``1 - shade``, or
``shade`` with ``negate``. Then

* ``trinary`` (the default): a wall where ``occ > occupied_thresh``;
* ``scale``: a wall where the pixel is opaque and ``occ > occupied_thresh``, or where the scaled
  value ``rint((occ - free_thresh) / (occupied_thresh - free_thresh) * 100)`` reaches 100;
* ``raw``: a wall where the pixel value ``round(shade * 255)`` is 100.
"""

from __future__ import annotations

import math
import pathlib

import numpy as np

MODES = ("trinary", "scale", "raw")
DEFAULT_OCCUPIED_THRESH = 0.65  # map_saver's defaults
DEFAULT_FREE_THRESH = 0.25
LETHAL_VALUE = 100  # an OccupancyGrid's occupied value, Nav2 static layer's lethal_cost_threshold


class MapFileError(ValueError):
    """A map file that cannot be used; the message names the file and the field."""


def _number(path, field: str, value) -> float:
    """The YAML ``value`` of ``field`` as a finite float (a number or a numeric string, never a bool)."""
    if isinstance(value, bool) or not isinstance(value, (int, float, str)):
        raise MapFileError(f"{path}: field '{field}': must be a number, got {value!r}")
    try:
        number = float(value)
    except ValueError:
        raise MapFileError(f"{path}: field '{field}': must be a number, got {value!r}") from None
    if not math.isfinite(number):
        raise MapFileError(f"{path}: field '{field}': must be a finite number, got {value!r}")
    return number


def _shade(image, with_alpha: bool) -> tuple[np.ndarray, np.ndarray]:
    """``(shade (H, W) float64 in [0, 1], opaque (H, W) bool)`` of a PIL image, as map_io reads it."""
    mode = image.mode
    if mode.startswith("I;16") or mode == "I":  # 16-bit grey (Pillow reads a 16-bit PGM as "I")
        grey = np.asarray(image, np.float64)
        if grey.size and (grey.min() < 0 or grey.max() > 65535):
            raise ValueError(f"{mode} pixels outside 0..65535")
        return grey / 65535.0, np.ones(grey.shape, bool)
    if mode in ("1", "L") and "transparency" not in image.info:  # grey: the mean of three equal channels
        grey = np.asarray(image.convert("L"), np.float64) / 255.0
        return grey, np.ones(grey.shape, bool)
    has_alpha = "A" in image.getbands() or "transparency" in image.info
    pixels = np.asarray(image.convert("RGBA" if has_alpha else "RGB"), np.float64) / 255.0
    rgb = pixels[..., :3]
    if not has_alpha:
        return rgb.mean(axis=-1), np.ones(rgb.shape[:2], bool)
    alpha = pixels[..., 3]
    channels = np.concatenate([rgb, alpha[..., None]], axis=-1) if with_alpha else rgb
    return channels.mean(axis=-1), alpha == 1.0


def read_ros_map(path) -> tuple[np.ndarray, float, tuple[float, float]]:
    """``(occupancy (H, W) float32 in {0, 1}, resolution_m, origin_xy_m)`` of a ROS map YAML, in
    the OccupancyGrid layout (row 0 at the bottom, :func:`models.inference.input_map`); walls as
    the module's docstring says.

    Raises:
      MapFileError: a missing or malformed field, an unreadable or oversized image (naming the
        file and the field).
    """
    import yaml
    from PIL import Image

    path = pathlib.Path(path)
    try:
        meta = yaml.safe_load(path.read_text())
    except (OSError, UnicodeDecodeError, yaml.YAMLError) as e:
        raise MapFileError(f"{path}: cannot read ({type(e).__name__}: {e})") from None
    if not isinstance(meta, dict):
        raise MapFileError(f"{path}: not a ROS map YAML (a mapping with image, resolution, origin)")
    for field in ("image", "resolution", "origin"):
        if field not in meta:
            raise MapFileError(f"{path}: field '{field}' is missing")
    image_name = meta["image"]
    if not isinstance(image_name, str) or not image_name.strip():
        raise MapFileError(f"{path}: field 'image': must be the image file's name, got {image_name!r}")
    resolution = _number(path, "resolution", meta["resolution"])
    if resolution <= 0:
        raise MapFileError(f"{path}: field 'resolution': must be a positive number of metres, got {resolution!r}")
    origin = meta["origin"]
    if not (isinstance(origin, list) and len(origin) in (2, 3)):
        raise MapFileError(f"{path}: field 'origin': must be [x, y, yaw], got {origin!r}")
    xyz = [_number(path, f"origin[{i}]", v) for i, v in enumerate(origin)]
    if len(xyz) == 3 and xyz[2] != 0:
        raise MapFileError(f"{path}: field 'origin': a rotated map (yaw {xyz[2]}) is not supported")
    occupied = _number(path, "occupied_thresh", meta.get("occupied_thresh", DEFAULT_OCCUPIED_THRESH))
    free = _number(path, "free_thresh", meta.get("free_thresh", DEFAULT_FREE_THRESH))
    for field, value in (("occupied_thresh", occupied), ("free_thresh", free)):
        if not 0 <= value <= 1:
            raise MapFileError(f"{path}: field '{field}': must be in [0, 1], got {value!r}")
    if not free < occupied:
        raise MapFileError(
            f"{path}: fields 'free_thresh', 'occupied_thresh': free ({free}) must be below occupied ({occupied})"
        )
    negate = meta.get("negate", 0)
    if isinstance(negate, str) and negate.strip() in ("0", "1"):
        negate = int(negate)
    if negate not in (0, 1) or not isinstance(negate, (bool, int)):
        raise MapFileError(f"{path}: field 'negate': must be 0 or 1 (or true, false), got {negate!r}")
    mode = meta.get("mode", "trinary")
    if mode not in MODES:
        raise MapFileError(f"{path}: field 'mode': must be one of {', '.join(MODES)}, got {mode!r}")

    image_path = path.parent / image_name
    try:
        with Image.open(image_path) as image:
            shade, opaque = _shade(image, with_alpha=mode == "trinary")
    except (OSError, ValueError, Image.DecompressionBombError) as e:
        raise MapFileError(f"{path}: field 'image': cannot read {image_path} ({e})") from None
    if shade.size == 0:
        raise MapFileError(f"{path}: field 'image': {image_path} has no pixels")
    occ = shade if negate else 1.0 - shade
    if mode == "trinary":
        wall = occ > occupied
    elif mode == "scale":
        scaled = np.rint((occ - free) / (occupied - free) * 100.0)
        wall = opaque & ((occ > occupied) | ((occ >= free) & (scaled >= LETHAL_VALUE)))
    else:
        wall = np.round(shade * 255.0) == LETHAL_VALUE
    occupancy = wall.astype(np.float32)[::-1]  # the image's top row is the map's last
    return np.ascontiguousarray(occupancy), resolution, (xyz[0], xyz[1])
