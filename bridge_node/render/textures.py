"""Procedural texture data of the scene: one tileable noise field with a 1/f spectrum over
five octaves, with its gradient, from which the shaders build snow relief, albedo patches
and waves by summing a few fetches at incommensurate scales and rotations (so that the sum
never repeats)."""
from __future__ import annotations

import numpy as np

NOISE_SIZE = 512  # texels per side; the field repeats once per texture (u, v in [0, 1))
NOISE_BAND = (4.0, 128.0)  # cycles per texture: features from 1/8 to 1/256 of the texture
# full ranges of height and derivatives (each of unit deviation) in the 8-bit texture, over
# four deviations either way; 8-bit textures are the fast path of Mesa's llvmpipe
NOISE_RANGE = (8.0, 8.0, 8.0)


def relief_noise(size: int = NOISE_SIZE, seed: int = 17) -> np.ndarray:
    """(size, size, 4) uint8: height and its derivatives along u and v, each scaled to unit
    deviation and mapped from -range/2..range/2 (NOISE_RANGE) to 0..255, and zero. Height
    amplitude falls as k^-1.6 over the band (snow relief); built in the frequency domain,
    so it tiles."""
    rng = np.random.default_rng(seed)
    k = np.fft.fftfreq(size, 1.0 / size)  # cycles per texture
    ku, kv = np.meshgrid(k, k, indexing="xy")
    radius = np.maximum(np.hypot(ku, kv), 1e-9)
    lo, hi = NOISE_BAND
    band = radius**-1.6 * (1.0 - np.exp(-((radius / lo) ** 4))) * np.exp(-((radius / hi) ** 4))
    spectrum = np.fft.fft2(rng.standard_normal((size, size))) * band
    out = np.zeros((size, size, 4), dtype=np.uint8)
    for c, factor in enumerate((1.0, 2j * np.pi * ku, 2j * np.pi * kv)):
        field = np.fft.ifft2(spectrum * factor).real
        out[..., c] = np.clip(np.round((field / field.std() / NOISE_RANGE[c] + 0.5) * 255.0), 0, 255)
    return out
