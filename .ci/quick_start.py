"""Print the README's quick start, one command line per line, exactly as the README writes them (.ci/run runs them)."""

import re
import sys
from pathlib import Path

readme = (Path(__file__).resolve().parent.parent / "README.md").read_text(encoding="utf-8")
block = re.search(r"^## Quick start\s+```bash\n(.*?)^```", readme, re.DOTALL | re.MULTILINE)
if block is None:
    sys.exit("README.md has no quick start block (## Quick start, then a bash block)")
print(block.group(1).strip())
