"""Getting data and models in and out of fohw.

Versioned JSON for models and results (:mod:`~fohw.io.jsonio`), safe file writing
(:mod:`~fohw.io.files`) and text tables (:mod:`~fohw.io.text`). The ``fohw`` command line is
:mod:`fohw.cli`.
"""

from .jsonio import load_model, load_result, save_model, save_result

__all__ = ["load_model", "load_result", "save_model", "save_result"]
