"""Makes the package importable from the source tree when the workspace is not sourced."""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "src"))
