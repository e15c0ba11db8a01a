"""A ROS map_server map read as Nav2 reads it (planners.learning.ros_map): each mode's walls on
hand-made pixels, the image's rows, numbers written as text, and bad fields named in one line."""

import numpy as np
import pytest
from PIL import Image

from socialnav.planners.learning import ros_map

YAML = "image: {image}\nresolution: 0.1\norigin: [0.0, 0.0, 0.0]\n"


def _read(tmp_path, pixels, extra: str = "") -> np.ndarray:
    """The occupancy of a one-row image of ``pixels`` (grey, RGB or RGBA by their shape), flattened."""
    Image.fromarray(np.asarray(pixels)[None]).save(tmp_path / "m.png")
    (tmp_path / "m.yaml").write_text(YAML.format(image="m.png") + extra)
    occupancy, _, _ = ros_map.read_ros_map(tmp_path / "m.yaml")
    assert occupancy.dtype == np.float32 and set(np.unique(occupancy)) <= {0.0, 1.0}
    return occupancy[0]


def test_trinary_walls_are_the_pixels_darker_than_the_threshold_or_lighter_with_negate(tmp_path):
    grey = np.array([0, 89, 90, 128, 254, 255], np.uint8)  # 1 - 89/255 = 0.651 > 0.65; 1 - 90/255 = 0.647
    assert _read(tmp_path, grey).tolist() == [1, 1, 0, 0, 0, 0]
    assert _read(tmp_path, grey, "negate: 1\n").tolist() == [0, 0, 0, 0, 1, 1]  # 166 / 255 = 0.651
    assert _read(tmp_path, grey, "occupied_thresh: 0.4\n").tolist() == [1, 1, 1, 1, 0, 0]


def test_a_colour_pixel_is_the_mean_of_its_channels_not_its_luma(tmp_path):
    """Nav2 averages red, green and blue: pure green (mean 85, occ 0.667) is a wall, where its
    luma (150, occ 0.41) would make it free."""
    rgb = np.array([[0, 255, 0], [255, 255, 255], [0, 0, 0], [120, 120, 120]], np.uint8)
    assert _read(tmp_path, rgb).tolist() == [1, 0, 1, 0]


def test_trinary_averages_opacity_in_and_scale_leaves_translucent_pixels_free(tmp_path):
    """In trinary mode an image with alpha averages its opacity in as a fourth channel: opaque grey
    60 reads (3 * 60 + 255) / 4 = 108.75 (occ 0.574, free) where without alpha it is a wall (occ
    0.765); transparent black reads 0 (a wall). In scale mode a pixel not fully opaque is unknown
    (free here); an opaque one is thresholded on its colour alone."""
    rgba = np.array([[60, 60, 60, 255], [0, 0, 0, 0], [0, 0, 0, 255], [0, 0, 0, 128], [255, 255, 255, 255]], np.uint8)
    assert _read(tmp_path, rgba).tolist() == [0, 1, 1, 1, 0]
    assert _read(tmp_path, rgba[:, :3]).tolist() == [1, 1, 1, 1, 0]
    assert _read(tmp_path, rgba, "mode: scale\n").tolist() == [1, 0, 1, 0, 0]


def test_a_grey_image_with_a_transparent_shade_has_alpha_as_nav2_reads_it(tmp_path):
    """A grey PNG whose tRNS chunk makes grey 0 transparent is read with an alpha channel, as
    Nav2's image library reads any PNG with a tRNS chunk: opaque grey 60 averages its opacity in
    (free), where the same pixels without the chunk make it a wall."""
    grey = np.array([[60, 0, 255]], np.uint8)
    (tmp_path / "m.yaml").write_text(YAML.format(image="m.png"))
    for transparency, walls in ((0, [0, 1, 0]), (None, [1, 1, 0])):
        extra = {} if transparency is None else {"transparency": transparency}
        Image.fromarray(grey, mode="L").save(tmp_path / "m.png", **extra)
        assert ros_map.read_ros_map(tmp_path / "m.yaml")[0][0].tolist() == walls, transparency


def test_scale_mode_makes_a_wall_where_the_scaled_value_rounds_to_100(tmp_path):
    """Between the thresholds scale mode publishes rint((occ - free) / (occupied - free) * 100):
    with free 0.2 and occupied 0.7, grey 78 (occ 0.694, 98.8) rounds to 99 and is free, grey 77 (occ
    0.698, 99.6) rounds to 100 and is a wall though not past occupied_thresh."""
    grey = np.array([76, 77, 78, 200], np.uint8)
    extra = "mode: scale\nfree_thresh: 0.2\noccupied_thresh: 0.7\n"
    assert _read(tmp_path, grey, extra).tolist() == [1, 1, 0, 0]
    assert _read(tmp_path, grey, "free_thresh: 0.2\noccupied_thresh: 0.7\n").tolist() == [1, 0, 0, 0]


def test_raw_mode_makes_a_wall_of_the_value_100_only(tmp_path):
    assert _read(tmp_path, np.array([99, 100, 101, 0, 255], np.uint8), "mode: raw\n").tolist() == [0, 1, 0, 0, 0]


def test_a_16_bit_image_is_read_over_its_whole_range(tmp_path):
    """A 16-bit PGM's grey 20000 of 65535 (occ 0.695) is a wall; cut to 8 bits (Pillow's
    conversion clips at 255) it read as white."""
    grey = np.array([[0, 20000, 40000, 65535]], np.uint16)
    (tmp_path / "m.pgm").write_bytes(b"P5\n4 1\n65535\n" + grey.astype(">u2").tobytes())
    (tmp_path / "m.yaml").write_text(YAML.format(image="m.pgm"))
    occupancy, _, _ = ros_map.read_ros_map(tmp_path / "m.yaml")
    assert occupancy[0].tolist() == [1, 1, 0, 0]


def test_the_image_top_row_is_the_map_last_and_numbers_may_be_text(tmp_path):
    pixels = np.array([[0, 0, 0], [255, 255, 255]], np.uint8)  # the top row black
    Image.fromarray(pixels).save(tmp_path / "m.pgm")
    (tmp_path / "m.yaml").write_text('image: m.pgm\nresolution: 5e-2\norigin: ["1.5", -2, 0]\nnegate: "0"\n')
    occupancy, resolution, origin = ros_map.read_ros_map(tmp_path / "m.yaml")
    assert occupancy.tolist() == [[0, 0, 0], [1, 1, 1]] and resolution == 0.05 and origin == (1.5, -2.0)
    (tmp_path / "m.yaml").write_text(f"image: {tmp_path / 'm.pgm'}\nresolution: 0.05\norigin: [0, 0]\nnegate: true\n")
    occupancy, _, _ = ros_map.read_ros_map(tmp_path / "m.yaml")  # an absolute image path, a 2-element origin
    assert occupancy.tolist() == [[1, 1, 1], [0, 0, 0]]


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (("resolution: 0.1", "resolution: -1"), "field 'resolution': must be a positive"),
        (("resolution: 0.1", "resolution: true"), "field 'resolution': must be a number, got True"),
        (("resolution: 0.1", "resolution: .nan"), "field 'resolution': must be a finite number"),
        (("resolution: 0.1", "resolution: ~"), "field 'resolution': must be a number, got None"),
        (("image: m.png\n", ""), "field 'image' is missing"),
        (("image: m.png", "image: none.png"), "field 'image': cannot read"),
        (("image: m.png", "image: ''"), "field 'image': must be the image file's name"),
        (("image: m.png", "image: m.yaml"), "field 'image': cannot read"),
        (("[0.0, 0.0, 0.0]", "[0.0, 0.0, 1.0]"), "rotated map"),
        (("[0.0, 0.0, 0.0]", "[.inf, 0.0, 0.0]"), r"field 'origin\[0\]': must be a finite number"),
        (("[0.0, 0.0, 0.0]", "[0.0, true, 0.0]"), r"field 'origin\[1\]': must be a number"),
        (("[0.0, 0.0, 0.0]", "[0.0]"), "field 'origin': must be"),
        (("origin", "origin: [0, 0]\nnegate: 2\n#"), "field 'negate': must be 0 or 1"),
        (("origin", "origin: [0, 0]\nnegate: 'yes please'\n#"), "field 'negate'"),
        (("origin", "origin: [0, 0]\nmode: grey\n#"), "field 'mode': must be one of trinary, scale, raw"),
        (("origin", "origin: [0, 0]\noccupied_thresh: 1.5\n#"), "field 'occupied_thresh': must be in"),
        (("origin", "origin: [0, 0]\nfree_thresh: 0.9\n#"), "free \\(0.9\\) must be below occupied \\(0.65\\)"),
        (("image: m.png\nresolution: 0.1\norigin: [0.0, 0.0, 0.0]\n", "just text"), "not a ROS map"),
    ],
)
def test_bad_map_files_are_named_with_their_field(tmp_path, change, message):
    Image.fromarray(np.full((4, 4), 254, np.uint8)).save(tmp_path / "m.png")
    bad = tmp_path / "m.yaml"
    bad.write_text(YAML.format(image="m.png").replace(*change))
    with pytest.raises(ros_map.MapFileError, match=message) as err:
        ros_map.read_ros_map(bad)
    assert str(bad) in str(err.value) and "\n" not in str(err.value)


def test_an_image_past_pillows_decompression_bomb_limit_is_refused_in_one_line(tmp_path, monkeypatch):
    """Pillow refuses an image of more than twice ``MAX_IMAGE_PIXELS`` (179 M by default) with an
    error that is not an OSError; it is named as the image field's, not a traceback."""
    Image.fromarray(np.full((30, 30), 254, np.uint8)).save(tmp_path / "m.png")
    (tmp_path / "m.yaml").write_text(YAML.format(image="m.png"))
    monkeypatch.setattr(Image, "MAX_IMAGE_PIXELS", 100)  # 900 pixels > 2 x 100
    with pytest.raises(ros_map.MapFileError, match="field 'image': cannot read .*m.png") as err:
        ros_map.read_ros_map(tmp_path / "m.yaml")
    assert "\n" not in str(err.value)
