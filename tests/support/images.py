"""Comparing rendered figures pixel by pixel."""

from io import BytesIO

import numpy as np
from PIL import Image


def pixels(png: bytes) -> np.ndarray:
    """The RGB pixels of PNG bytes, as integers (differences do not wrap)."""
    return np.asarray(Image.open(BytesIO(png)).convert("RGB")).astype(int)
