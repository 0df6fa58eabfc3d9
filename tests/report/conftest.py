"""Make the shared synthetic-data module (tests/figures/synthetic_data.py) importable here."""
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "figures"))
