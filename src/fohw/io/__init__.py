"""Getting data and models in and out of fohw.

Versioned JSON for models and results (:mod:`~fohw.io.jsonio`), safe file writing
(:mod:`~fohw.io.files`) and the ``fohw`` command line (:mod:`~fohw.io.cli`).
"""

from .jsonio import load_model, load_result, save_model, save_result

__all__ = ["load_model", "load_result", "save_model", "save_result"]
