"""socialnav.data: what the toolkit loads, shipped with the package: the warehouse scenario
(:data:`WAREHOUSE_DIR`) and the seeds' social-navigation scenes (:data:`SCENES_DIR`, one JSON
file each). Code finds it through :data:`DATA_DIR`, so an installed package works from any folder."""

import pathlib

DATA_DIR = pathlib.Path(__file__).resolve().parent
WAREHOUSE_DIR = DATA_DIR / "warehouse"
SCENES_DIR = DATA_DIR / "scenes"

__all__ = ["DATA_DIR", "SCENES_DIR", "WAREHOUSE_DIR"]
