"""The citation metadata agree with each other and with the newest CHANGELOG entry: one version,
one release date, one repository, and every paper's DOI where a reader looks for it."""

import json
import re
import tomllib

import pandas as pd
import yaml

import mtaccuracy
from mtaccuracy.compendium.provenance import ROOT


def _newest_changelog_entry() -> tuple[str, str]:
    m = re.search(r"^## (\d+\.\d+\.\d+) \((\d{4}-\d{2}-\d{2})\)$",
                  (ROOT / "CHANGELOG.md").read_text(encoding="utf-8"), re.M)
    assert m, "CHANGELOG.md has no '## X.Y.Z (YYYY-MM-DD)' entry"
    return m.group(1), m.group(2)


def test_one_version_and_one_release_date_everywhere():
    version, date = _newest_changelog_entry()
    cff = yaml.safe_load((ROOT / "CITATION.cff").read_text(encoding="utf-8"))
    zenodo = json.loads((ROOT / ".zenodo.json").read_text(encoding="utf-8"))
    project = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    assert {str(cff["version"]), zenodo["version"], project["version"],
            mtaccuracy.__version__} == {version}
    assert {str(cff["date-released"]), zenodo["publication_date"]} == {date}
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    assert f"version {version}" in readme and f"`v{version}`" in readme


def test_one_repository_everywhere():
    cff = yaml.safe_load((ROOT / "CITATION.cff").read_text(encoding="utf-8"))
    zenodo = json.loads((ROOT / ".zenodo.json").read_text(encoding="utf-8"))
    repo = cff["repository-code"]
    assert re.fullmatch(r"https://github\.com/[\w.-]+/[\w.-]+", repo)
    assert repo in {r["identifier"] for r in zenodo["related_identifiers"]}
    assert repo in (ROOT / "README.md").read_text(encoding="utf-8")
    owner, name = repo.rsplit("/", 2)[-2:]
    assert cff["url"] == f"https://{owner}.github.io/{name}/"  # the book, on GitHub Pages


def test_every_papers_doi_is_where_a_reader_looks():
    index = pd.read_csv(ROOT / "data" / "papers" / "index.csv", dtype=str, keep_default_na=False)
    cff = (ROOT / "CITATION.cff").read_text(encoding="utf-8")
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    head = readme.split("## Running, in more detail")[0]  # the README's first screen
    zenodo = (ROOT / ".zenodo.json").read_text(encoding="utf-8")
    dois = [d for d in index["doi"] if d]
    assert len(dois) == 3
    for doi in dois:
        assert doi in cff and f"https://doi.org/{doi}" in head and doi in zenodo
    assert len(head.splitlines()) <= 45  # what a newcomer reads before the details
