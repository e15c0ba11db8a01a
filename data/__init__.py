"""data: what the toolkit loads, shipped with the package (the warehouse scenario; the
social-navigation scenes join in later issues). Code finds it through :data:`DATA_DIR`, so an
installed package works from any folder."""

import pathlib

DATA_DIR = pathlib.Path(__file__).resolve().parent
WAREHOUSE_DIR = DATA_DIR / "warehouse"
