"""MkDocs hooks of the documentation site (``mkdocs.yml``: ``hooks``).

Pages that other work adds to ``docs/`` join the navigation where they belong as soon as the
file exists, so the strict build (which fails on a page missing from the navigation) never
lists a page that is not there yet.
"""

from __future__ import annotations

from pathlib import Path

#: navigation section -> [(title, page)], added after the section's last entry when the page
#: exists
OPTIONAL_PAGES = {"Explanation": [("Time to result", "time-to-result.md")]}


def on_config(config):
    docs = Path(config["docs_dir"])
    for section in config["nav"] or []:
        if not isinstance(section, dict):
            continue
        for title, entries in section.items():
            listed = {next(iter(e.values())) for e in entries if isinstance(e, dict)}
            for name, page in OPTIONAL_PAGES.get(title, []):
                if (docs / page).is_file() and page not in listed:
                    entries.append({name: page})
    return config
