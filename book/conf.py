"""Sphinx configuration of the compendium's book (``make book``).

The pages are generated into ``build/book/src`` by ``python -m mtaccuracy.apps.book``, which
copies this file there: the executed notebooks are shown as committed (MyST-NB, never executed),
the library's reference comes from its numpydoc docstrings, and every script the pages need
(MathJax from the ``jupyter-server-mathjax`` package, DataTables from ``itables``) is served from
the book itself, so it reads offline.
"""

from mtaccuracy.apps import book

project = "mtaccuracy"
author = "The mtaccuracy team"
copyright = "the mtaccuracy team; text and figures CC-BY-4.0, code MIT"

extensions = ["myst_nb", "sphinx.ext.autodoc", "sphinx.ext.mathjax", "numpydoc"]
source_suffix = {".md": "myst-nb", ".ipynb": "myst-nb"}
exclude_patterns = ["_build", "**.ipynb_checkpoints", "data/**", "figures/**"]
master_doc = "index"
language = "en"

# the committed notebooks are the results: shown, never executed by the build
nb_execution_mode = "off"
nb_merge_streams = True
myst_enable_extensions = ["dollarmath", "amsmath", "colon_fence", "html_image"]
myst_heading_anchors = 3
suppress_warnings = ["myst.header", "mystnb.unknown_mime_type", "misc.highlighting_failure"]

# the library's reference
autodoc_member_order = "bysource"
autodoc_typehints = "none"
# long signatures one parameter per line, so that API pages do not scroll sideways on a phone
maximum_signature_line_length = 60
numpydoc_show_class_members = False
numpydoc_validation_checks = set()

# MathJax 2.7 (its combined TeX config, HTML-CSS output) from the jupyter-server-mathjax package, copied into _static/mathjax by the build
mathjax_path = "mathjax/MathJax.js?config=TeX-AMS-MML_HTMLorMML-full"
mathjax2_config = {
    "tex2jax": {"inlineMath": [["\\(", "\\)"]], "displayMath": [["\\[", "\\]"]],
                "processEscapes": True, "processClass": "math|output_area|tex2jax_process",
                "ignoreClass": "tex2jax_ignore|document"},
    # the package ships the STIX-Web fonts only (as Jupyter's classic notebook used them)
    "HTML-CSS": {"availableFonts": [], "imageFont": None, "preferredFont": None,
                 "font": "STIX-Web", "webFont": "STIX-Web", "linebreaks": {"automatic": True}},
    "showMathMenu": False,
    "messageStyle": "none",
}

html_theme = "sphinx_book_theme"
html_title = "mtaccuracy"
html_static_path = ["_static"]
html_css_files = ["mtaccuracy.css"]
html_last_updated_fmt = None
html_context = {"default_mode": "light"}
html_copy_source = False
html_show_sourcelink = False
# the repository is named once, in CITATION.cff (the Binder launch button of the notebook
# pages follows it; the repository links are in the pages' text: the header's button would load
# a 110 kB icon font for one icon)
html_theme_options = {
    "repository_url": book.repository(),
    "repository_branch": "HEAD",
    "path_to_docs": "",
    "launch_buttons": {"binderhub_url": "https://mybinder.org", "notebook_interface": "jupyterlab"},
    "show_toc_level": 2,
    "home_page_in_toc": True,
    "use_download_button": False,
    "use_fullscreen_button": False,
    "navigation_with_keys": False,
}


def _skip_generated(app, what, name, obj, skip, options):
    """scikit-learn generates metadata-routing methods (``set_fit_request``, ...) on every
    estimator class; their docstrings point into scikit-learn's own docs."""
    if name == "get_metadata_routing" or (name.startswith("set_") and name.endswith("_request")):
        return True
    return skip


def setup(app):
    app.connect("autodoc-skip-member", _skip_generated)
