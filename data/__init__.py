"""socialnav.data: what the toolkit loads, shipped with the package: the warehouse scenario
(:data:`WAREHOUSE_DIR`) and the seeds' social-navigation scenes (:data:`SCENES_DIR`, one JSON
file each; the recorded-crowd scenes in :data:`RECORDED_SCENES_DIR`; the seeds' scenes at other
angles, which the papers did not test, in :data:`GEOMETRY_SCENES_DIR`). Code finds it through
:data:`DATA_DIR`, so an installed package works from any folder."""

import pathlib

DATA_DIR = pathlib.Path(__file__).resolve().parent
WAREHOUSE_DIR = DATA_DIR / "warehouse"
SCENES_DIR = DATA_DIR / "scenes"
RECORDED_SCENES_DIR = SCENES_DIR / "recorded"
GEOMETRY_SCENES_DIR = SCENES_DIR / "geometry"

__all__ = ["DATA_DIR", "GEOMETRY_SCENES_DIR", "RECORDED_SCENES_DIR", "SCENES_DIR", "WAREHOUSE_DIR"]
