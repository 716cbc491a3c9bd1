"""Channel images side by side: a panorama image, and a video of them (PyAV, whose wheel
carries its own FFmpeg encoders)."""
from __future__ import annotations

from pathlib import Path

import av
import numpy as np
from PIL import Image

from bridge_node.common.output_files import OutputFile

MAX_VIDEO_WIDTH = 1920  # px: wider panoramas are scaled down for the video


def side_by_side(images: list[np.ndarray]) -> np.ndarray:
    """Images (h_i, w_i, 3) uint8 in a row, padded to the tallest: (h, sum w_i, 3)."""
    height = max(img.shape[0] for img in images)
    return np.hstack([np.pad(img, ((0, height - img.shape[0]), (0, 0), (0, 0))) for img in images])


def save_png(image: np.ndarray, path: Path, what: str = "image") -> Path:
    """Write the image as PNG whatever the file name's extension, atomically, replacing
    only a regular file (``what``: the option or kind of output, for the messages)."""
    output = OutputFile(path, what)
    with output as tmp:
        Image.fromarray(image).save(tmp, format="PNG")
    return output.path


class VideoWriter:
    """H.264 (or MPEG-4 where libx264 is missing) at ``fps``; frames of any size are scaled
    to the first frame's size, at most MAX_VIDEO_WIDTH wide, with even sides."""

    def __init__(self, path: Path, fps: float, what: str = "video") -> None:
        self.output = OutputFile(path, what)  # written beside, put in place by close()
        self.path, self.fps = self.output.path, fps
        self.container = av.open(str(self.output.tmp), "w")
        self.stream = None
        self.frames = 0

    def write(self, image: np.ndarray) -> None:
        if self.stream is None:
            scale = min(1.0, MAX_VIDEO_WIDTH / image.shape[1])
            codec = "libx264" if "libx264" in av.codecs_available else "mpeg4"
            self.stream = self.container.add_stream(codec, rate=max(1, round(self.fps)))
            self.stream.width = int(image.shape[1] * scale) // 2 * 2
            self.stream.height = int(image.shape[0] * scale) // 2 * 2
            self.stream.pix_fmt = "yuv420p"
        size = (self.stream.width, self.stream.height)
        if (image.shape[1], image.shape[0]) != size:
            image = np.asarray(Image.fromarray(image).resize(size, Image.BILINEAR))
        frame = av.VideoFrame.from_ndarray(np.ascontiguousarray(image), format="rgb24")
        self.container.mux(self.stream.encode(frame))
        self.frames += 1

    def close(self) -> None:
        """Flush the encoder, close the file and put it in place; safe to call twice."""
        if self.container is not None:
            with self.output:
                if self.stream is not None:
                    self.container.mux(self.stream.encode(None))
                self.container.close()
                self.container = None
