"""Projector-channel rendering of the ice scene with moderngl (EGL offscreen on a headless node)."""
