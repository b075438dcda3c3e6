"""Shared pytest setup (keep it small).

Figures built in tests render off-screen (Agg). Notebook kernels are unaffected: the report
runner starts them with the inline backend whatever MPLBACKEND says.
"""

import matplotlib

matplotlib.use("Agg")
