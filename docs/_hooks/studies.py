"""MkDocs hook: serve the repository's studies/ folder beside the manual, under studies/.

In the repository the manual (docs/) and the studies (studies/) are sibling folders, so a page
links a study as ``../studies/2026-11-name/README.md`` and a study links a page as
``../../docs/page.md``: both read right on a code host. This hook adds every file of studies/
to the site and rewrites those two prefixes, so the same links resolve in the built site and
``mkdocs build --strict`` checks them like any other.
"""

from __future__ import annotations

import re
from pathlib import Path

from mkdocs.structure.files import File, Files, InclusionLevel

ROOT = Path(__file__).resolve().parents[2]
STUDIES = ROOT / "studies"


def on_files(files: Files, config) -> Files:
    """Every file under studies/ joins the site at ``studies/<same path>``."""
    for path in sorted(STUDIES.rglob("*")):
        if path.is_file() and "__pycache__" not in path.parts:
            uri = path.relative_to(ROOT).as_posix()
            files.append(
                File(
                    uri,
                    src_dir=str(ROOT),
                    dest_dir=config["site_dir"],
                    use_directory_urls=config["use_directory_urls"],
                    inclusion=InclusionLevel.NOT_IN_NAV,  # listed by docs/studies.md
                )
            )
    return files


def on_page_markdown(markdown: str, page, config, files) -> str:
    """Links written for the repository become links inside the site."""
    if page.file.src_uri.startswith("studies/"):
        return re.sub(r"\]\((\.\./\.\./)docs/", r"](\1", markdown)
    return re.sub(r"\]\(\.\./studies/", "](studies/", markdown)
