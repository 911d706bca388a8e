"""The repository stands alone: it cites no file outside itself (the seed papers by title and
equation number, docs/references.md; conventions and parameter sources in docs/)."""
from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SKIP = {".git", "__pycache__", ".pytest_cache", ".hypothesis", "demo-output", "build", "dist"}
OUTSIDE = re.compile(r"(?<![\w-])(\.\./)?" + "shared" + r"/")


def _text_files():
    for path in ROOT.rglob("*"):
        if any(part in SKIP or part.endswith(".egg-info") for part in path.relative_to(ROOT).parts):
            continue
        if path.is_file() and path.suffix in {".py", ".md", ".toml", ".json", ".txt", ".c", ".h", ".cfg", ""}:
            try:
                yield path, path.read_text(encoding="utf-8")
            except (UnicodeDecodeError, OSError):
                continue


def test_no_reference_to_files_outside_the_repository():
    found = [f"{p.relative_to(ROOT)}:{i}" for p, text in _text_files()
             for i, line in enumerate(text.splitlines(), 1) if OUTSIDE.search(line)]
    assert found == []


def test_the_cited_documents_exist():
    for name in ("references.md", "pam-conventions.md", "exo-parameters.md"):
        assert (ROOT / "docs" / name).is_file(), name
    refs = (ROOT / "docs" / "references.md").read_text(encoding="utf-8")
    assert "Detailed Dynamic Model of Antagonistic PAM System" in refs and "Kalman-PID" in refs
