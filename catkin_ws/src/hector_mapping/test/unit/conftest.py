"""Makes the package and its test fixtures (test/sim2d.py, test/indoor.py) importable from the source tree."""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "src"))
sys.path.insert(0, os.path.join(os.path.dirname(__file__), ".."))
