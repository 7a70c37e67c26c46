"""Sphinx configuration of the fohw documentation (build: see docs/index.md).

The build needs no network: MathJax is served from the build's own ``_static`` (the
``sphinx-mathjax-offline`` package), intersphinx reads the inventories in ``_intersphinx/``, and
the theme's assets are in its package. What is made at build time (the API pages from
``fohw.__all__``, the gallery of the examples, the executed tutorial) is written by
``_ext/fohw_docs.py`` into ``api/``, ``gallery/`` and ``_executed/`` of this folder.
"""

import sys
from pathlib import Path

import fohw

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE / "_ext"))

project = "fohw"
author = "fohw developers"
copyright = "fohw developers"
release = version = fohw.__version__
extensions = ["myst_parser", "sphinx.ext.autodoc", "sphinx.ext.autosummary", "numpydoc",
              "sphinx.ext.mathjax", "sphinx-mathjax-offline", "sphinx.ext.intersphinx", "fohw_docs"]
source_suffix = {".md": "markdown", ".rst": "restructuredtext"}
master_doc = "index"
exclude_patterns = ["_build", "README.md", "_intersphinx", "_ext", "_templates", "_executed",
                    "gallery/*/*"]
templates_path = ["_templates"]
myst_enable_extensions = ["dollarmath", "amsmath"]
myst_heading_anchors = 3
numpydoc_show_class_members = False
numpydoc_validation_checks = set()
# Parameter types link where an inventory has them (Python's builtins, SciPy); NumPy has none here,
# so its names in numpydoc's default aliases are mapped to plain text.
numpydoc_xref_param_type = True
numpydoc_xref_ignore = "all"
numpydoc_xref_aliases = {name: name for name in (
    "array", "ndarray", "np.ndarray", "array-like", "array_like", "scalar", "dtype",
    "RandomState", "np.random.RandomState", "random_state", "matplotlib_axes", "Axes", "Figure")}
autodoc_default_options = {"undoc-members": False}
autodoc_typehints = "none"
autosummary_generate = True
autosummary_ignore_module_all = False
suppress_warnings = ["myst.header"]

# Math: MathJax 3 from the build's _static (sphinx-mathjax-offline copies it there and sets
# mathjax_path); never a CDN.
# Intersphinx: only local inventories (see _intersphinx/README.md); a missing one is an error.
intersphinx_mapping = {
    "python": ("https://docs.python.org/3.11/", str(HERE / "_intersphinx" / "python-3.11.inv")),
    "scipy": ("https://docs.scipy.org/doc/scipy-1.10.1/", str(HERE / "_intersphinx" / "scipy-1.10.1.inv")),
}

html_theme = "pydata_sphinx_theme"
html_title = f"fohw {version}"
html_static_path = ["_static"]
html_css_files = ["fohw.css"]
html_theme_options = {
    "navigation_with_keys": False,
    "show_toc_level": 2,
    "header_links_before_dropdown": 6,
    "secondary_sidebar_items": ["page-toc"],
    "footer_start": ["copyright"],
    "footer_end": ["sphinx-version"],
}
# The left sidebar lists a section's pages: the API pages and the gallery's; other pages have none.
html_sidebars = {"*": [], "api/*": ["sidebar-nav-bs"], "gallery/*": ["sidebar-nav-bs"]}

# The gallery (see _ext/fohw_docs.py). Every example runs with --fast while the pages are built,
# two at a time, except these two, the slowest even in fast mode (robot_arm about 10 s,
# cascaded_tanks about 6 s on a quiet 2-core machine, against 1.3 to 4.5 s for the others):
# their pages show the committed figures of the full runs instead, and say so.
fohw_gallery_examples = "../examples"
fohw_gallery_jobs = 2
fohw_gallery_not_executed = {
    "robot_arm.py": ["figures/robot_arm_figure_7.png", "figures/robot_arm_figure_8.png",
                     "figures/robot_arm_figure_9.png", "figures/robot_arm_simulation.png"],
    "cascaded_tanks.py": ["figures/cascaded_tanks.png"],
}
fohw_gallery_intro = """
Every script in ``examples/`` reproduces one table or figure of the paper or one study of these
pages. Each takes ``--outdir DIR`` (where it writes its tables and figures) and ``--fast`` (a
smaller run for a quick look; the test suite runs every example that way). While these pages were
built, each example ran with ``--fast`` and its page shows what it wrote and printed, so the
numbers are a quick run's, not the full run's that the study pages quote. Two examples
(``robot_arm.py`` and ``cascaded_tanks.py``, the slowest) were not run; their pages say so and
show the committed figures of their full runs.
"""
fohw_executed = ["tutorial.py"]
