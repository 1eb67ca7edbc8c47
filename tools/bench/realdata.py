"""Where the real images are, and their reference values (one home for tests and benches).

* The catadioptric set (OpenCV's ``cv::omnidir`` test data, no licence file) is used in
  place from ``<repo>/../shared/realdata`` (CI clones the repository beside a
  ``shared/`` folder); whoever needs it skips, with :data:`CATADIOPTRIC_MISSING`, when
  it is absent.
* The fisheye pair (Kimera-VIO's test data, BSD 2-clause) is vendored under
  ``tests/fixtures/realdata/fisheye_pair`` with its ``LICENSE.BSD``: one copy, used by
  every test and benchmark from there.
"""

from __future__ import annotations

from pathlib import Path

from shared.chessboard import Chessboard

REPO = Path(__file__).resolve().parents[2]
REALDATA_DIR = REPO.parent / "shared" / "realdata"
CATADIOPTRIC_DIR = REALDATA_DIR / "catadioptric"
CATADIOPTRIC_MISSING = f"{CATADIOPTRIC_DIR} is absent (real images, not vendored: no licence)"
#: The board of the catadioptric set: 9x6 inner corners. The square's side is not
#: given with the set; it scales the board poses only, not the intrinsics.
CATADIOPTRIC_BOARD = Chessboard(cols=9, rows=6, square_m=0.025)
#: OpenCV's reference for the set (``test_omnidir.cpp``), image size 1280x960: px, px,
#: px, px, dimensionless.
CATADIOPTRIC_REFERENCE = {"fx": 384.81, "fy": 386.68, "cx": 631.96, "cy": 432.67, "xi": 0.936}
#: Tolerances of the issue: focal lengths within 1 %, xi within 0.02.
FOCAL_TOLERANCE = 0.01
XI_TOLERANCE = 0.02

FISHEYE_PAIR_DIR = REPO / "tests" / "fixtures" / "realdata" / "fisheye_pair"
FISHEYE_LEFT_IMAGE = FISHEYE_PAIR_DIR / "left_fisheye_img_0.png"
FISHEYE_RIGHT_IMAGE = FISHEYE_PAIR_DIR / "right_fisheye_img_0.png"
FISHEYE_LEFT_YAML = FISHEYE_PAIR_DIR / "left_sensor_fisheye.yaml"
FISHEYE_RIGHT_YAML = FISHEYE_PAIR_DIR / "right_sensor_fisheye.yaml"
#: Tolerances of the issue for the pair's relative pose, degrees.
ROTATION_TOLERANCE_DEG = 0.3
DIRECTION_TOLERANCE_DEG = 1.5
