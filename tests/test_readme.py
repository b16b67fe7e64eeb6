"""The README and the guides cannot go stale: a fresh run of their examples must print what
they show (one test per document, so that test workers share them out)."""

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
#: A document's run may take this long (s).  docs/instruments.md designs eight plans, two
#: of them a camera's (about 9 min alone, 11 min beside the other slow tests on CI's two
#: cores): the timeout is there to stop a hung command, not to time the examples.
DOCUMENT_TIMEOUT = 1800
DOCUMENTS = ["README.md", *sorted(p.relative_to(ROOT).as_posix() for p in ROOT.glob("docs/*.md"))]


@pytest.mark.slow
@pytest.mark.parametrize("document", DOCUMENTS)
def test_document_matches_a_fresh_run_of_its_examples(document: str) -> None:
    done = subprocess.run(
        [sys.executable, str(ROOT / "tools" / "readme.py"), "--check", str(ROOT / document)],
        capture_output=True,
        text=True,
        timeout=DOCUMENT_TIMEOUT,
        check=False,
    )
    assert done.returncode == 0, done.stdout + done.stderr
