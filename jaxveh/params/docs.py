"""Write the data-file documentation: ``python -m jaxveh.params.docs [PATH]``."""

import sys
from pathlib import Path

from ._docs import render

if __name__ == "__main__":
    path = Path(sys.argv[1]) if len(sys.argv) > 1 else Path("docs/data.md")
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(render())
    print(f"wrote {path}")
