"""The README and the guides cannot go stale: a fresh run of their examples must print what
they show (one test per document, so that test workers share them out)."""

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
DOCUMENTS = ["README.md", *sorted(p.relative_to(ROOT).as_posix() for p in ROOT.glob("docs/*.md"))]


@pytest.mark.slow
@pytest.mark.parametrize("document", DOCUMENTS)
def test_document_matches_a_fresh_run_of_its_examples(document: str) -> None:
    done = subprocess.run(
        [sys.executable, str(ROOT / "tools" / "readme.py"), "--check", str(ROOT / document)],
        capture_output=True,
        text=True,
        timeout=600,
        check=False,
    )
    assert done.returncode == 0, done.stdout + done.stderr
