"""Figures tests: Agg backend, synthetic contract-shaped data (synthetic_data.py)."""
import os
import sys
from pathlib import Path

os.environ.setdefault("MPLBACKEND", "Agg")
sys.path.insert(0, str(Path(__file__).resolve().parent))
