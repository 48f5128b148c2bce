"""Image message payloads to arrays, with padding, byte order and bad sizes."""
import numpy as np
import pytest

from circle_detector.images import image_to_array, to_bgr


def test_bgr_with_row_padding():
    img = np.arange(2 * 3 * 3, dtype=np.uint8).reshape(2, 3, 3)
    data = b"".join(row.tobytes() + b"\x00\x00" for row in img)
    out = image_to_array(2, 3, "bgr8", 11, 0, data)
    assert np.array_equal(out, img)


def test_16uc1_big_endian():
    d = np.array([[1, 2], [3, 1000]], dtype=">u2")
    out = image_to_array(2, 2, "16UC1", 4, 1, d.tobytes())
    assert out.dtype == np.uint16 and out[1, 1] == 1000


def test_bad_sizes_and_encodings():
    with pytest.raises(ValueError):
        image_to_array(2, 2, "bgr8", 6, 0, b"\x00" * 5)
    with pytest.raises(ValueError):
        image_to_array(2, 2, "yuv422", 4, 0, b"\x00" * 8)
    with pytest.raises(ValueError):
        to_bgr(np.zeros((2, 2), np.uint8), "mono8")


def test_rgb_to_bgr():
    rgb = np.array([[[1, 2, 3]]], np.uint8)
    assert to_bgr(rgb, "rgb8").tolist() == [[[3, 2, 1]]]
