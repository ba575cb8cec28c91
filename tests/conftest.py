import sys
from pathlib import Path

# tests/chain_plant.py is a test helper module, imported by name.
sys.path.insert(0, str(Path(__file__).resolve().parent))
