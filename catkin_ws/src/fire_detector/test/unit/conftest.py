"""Makes the package importable from the source tree even before catkin_make has run."""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "src"))
sys.path.insert(0, os.path.join(os.path.dirname(__file__), ".."))  # the test fixtures (synthetic_*.py)
sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "..", "mbzirc_arena", "src"))
