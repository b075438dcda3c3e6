"""Helpers the tests share: flights and log writers that make records with known answers,
the NumPy references the compiled kernels replaced, and where the shared public logs are."""
