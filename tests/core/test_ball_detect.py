"""The suggested circle (core.ball_detect) on computed photos of a grey ball."""

import numpy as np
import pytest

from sh_lighting.core.ball_camera import camera_looking
from sh_lighting.core.ball_detect import detect_ball
from sh_lighting.core.photo import ball_picture

LIGHT = np.array(
    [[3.0, 2.5, 2.0], [0.5, 0.4, 0.2], [1.1, 1.0, 0.9], [-0.4, -0.2, 0.0], [0.2, 0.1, 0.0],
     [0.0, -0.2, 0.1], [0.3, 0.3, 0.2], [0.1, 0.1, 0.3], [-0.2, 0.0, 0.2]]
)
FRONT = camera_looking((0.0, 1.0, 0.0))


def photo(height, width, circle, background, noise=0.02, seed=0):
    """A grey ball at ``circle`` over a textured background of mean ``background``, with
    ``noise`` per pixel."""
    yy, xx = np.mgrid[:height, :width]
    behind = background * (1.0 + 0.5 * np.sin(xx / 37.0) * np.cos(yy / 23.0))
    ball = ball_picture(LIGHT, height, width, circle, FRONT, background=-1.0)
    picture = np.where(ball >= 0.0, ball, behind[..., None])
    rng = np.random.default_rng(seed)
    return picture * (1.0 + noise * rng.standard_normal(picture.shape))


@pytest.mark.parametrize("height, width, circle, background", [
    (96, 96, (48.0, 48.0, 44.0), 0.0),  # the ball filling a black frame
    (300, 480, (301.3, 140.7, 61.2), 0.05),  # off-centre, a textured background
    (1080, 1920, (1300.4, 500.2, 180.6), 0.08),  # HD: found on a 256 px copy, then refined
    (200, 200, (100.0, 100.0, 20.0), 0.2),  # small, a background brighter than its dark side
])
def test_the_ball_is_found_to_a_fraction_of_a_pixel(height, width, circle, background):
    guess = detect_ball(photo(height, width, circle, background))
    assert guess is not None
    # Measured: within 0.1 px in centre and radius, 88-100 % of the rim on the circle (less
    # where the background is as bright as the ball's rim).
    assert np.hypot(guess.cx - circle[0], guess.cy - circle[1]) < 0.5
    assert guess.r == pytest.approx(circle[2], abs=0.5)
    assert guess.score > 0.8
    assert "ball found at" in guess.summary()


def test_a_partly_hidden_ball_is_found_with_the_part_of_its_rim_seen():
    picture = photo(300, 480, (240.0, 150.0, 80.0), 0.05)
    picture[150:, 240:] = 0.02  # a dark card over the lower right quarter
    guess = detect_ball(picture)
    assert guess is not None
    # Measured: within 0.1 px, 75 % of the rim (the card's rays find no edge)
    assert np.hypot(guess.cx - 240.0, guess.cy - 150.0) < 0.5
    assert guess.r == pytest.approx(80.0, abs=0.5)
    assert 0.6 < guess.score < 0.85


def test_no_ball_no_suggestion():
    rng = np.random.default_rng(1)
    assert detect_ball(rng.uniform(0.0, 1.0, (200, 200, 3))) is None  # noise
    assert detect_ball(np.zeros((200, 200, 3))) is None  # black
    assert detect_ball(np.full((4, 4, 3), 0.5)) is None  # too small to hold a ball
