"""The robot's vision configs: Harris features, ZNCC matching, key image selection,
relative pose, the path state and localization in the memory.

Tables ``[features]``, ``[matching]``, ``[teach]``, ``[path_state]`` and ``[localize]``
of a vmnav config file (:mod:`robot.config`).
"""

from __future__ import annotations

import copy
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from shared.camera_model import CameraModel
from shared.config import require

#: The default lens's scale at the image centre, px/rad (as
#: :func:`robot.vision.features.pixels_per_radian` computes it): the lens every
#: pixel-valued vision key was sized for, and the defaults below still are.
_DEFAULT_LENS = CameraModel.default()
_DEFAULT_LENS_PX_PER_RAD = float(_DEFAULT_LENS.K[0, 0] / (1.0 + _DEFAULT_LENS.xi))


def degrees_on_default_lens(px: float) -> float:
    """The angle that spans ``px`` pixels at the default lens's centre, degrees."""
    return math.degrees(px / _DEFAULT_LENS_PX_PER_RAD)


#: Front-end methods (:mod:`robot.vision.front_end`): the paper's Harris corners with ZNCC
#: patches, and OpenCV's descriptors (TEBLID and BEBLID from opencv-contrib).
FRONT_END_METHODS = ("harris-zncc", "orb", "akaze", "sift", "teblid", "beblid")


@dataclass(frozen=True, slots=True)
class FeatureConfig:
    """The vision front end: its method, and the paper's Harris corners and ZNCC patches
    (Courbon et al. 2008, sec. III-A).

    Defaults follow OpenCV's Harris (``k`` = 0.04, 3x3 block, 3x3 Sobel) and the
    reference benchmark (300 corners, 11x11 patches on the default lens).

    Windows are angles on the sphere (``*_deg``), turned into pixels through the camera
    model's scale at the image centre (:func:`robot.vision.front_end.pixels_per_radian`;
    174 px/rad on the default lens), so a lens of another resolution or focal length
    sees the same part of the scene. The Harris block and the sub-pixel window stay in
    pixels: they are about image gradients and pixel noise, not about the scene.
    """

    method: str = "orb"
    """One of ``FRONT_END_METHODS``: how points are detected and described. ``orb`` (upright
    ORB on FAST corners spread over a grid) was chosen by measurement on the real fisheye
    pair and in the simulator, against the paper's ``harris-zncc`` (docs/front-end.md)."""
    max_corners: int = 300
    """Keep at most this many corners, strongest Harris response first."""
    quality_level: float = 0.01
    """Reject corners whose response is below this fraction of the frame's strongest, in (0, 1)."""
    min_distance_deg: float = degrees_on_default_lens(8.0)
    """Minimum angle between two Harris corners, degrees (greedy, strongest first); 8 px on
    the default lens, 2.64 degrees."""
    block_size_px: int = 3
    """Side of the window summing the gradient products of the Harris matrix, px (odd)."""
    harris_k: float = 0.04
    """Harris & Stephens' k in det(M) - k trace(M)^2 (dimensionless)."""
    patch_size_deg: float = degrees_on_default_lens(11.0)
    """Side of the square ZNCC patch, degrees: P px, the nearest odd >= 3; 11 px on the
    default lens, 3.63 degrees; a descriptor has P*P values."""
    subpixel_half_window_px: int = 3
    """Half side of the cv2.cornerSubPix window, px; 0 keeps integer corner positions."""
    fast_threshold: int = 12
    """Methods on FAST corners (orb, teblid, beblid): the absolute contrast threshold,
    grey levels (a corner needs 9 contiguous circle pixels this much brighter or darker)."""
    fast_threshold_low: int = 5
    """Methods on FAST corners: a grid cell that found fewer corners than its share is
    searched again with this threshold, grey levels (a local floor: a dim part of the view
    keeps corners); >= ``fast_threshold`` turns the second search off."""
    grid_cells: int = 8
    """Methods on FAST corners: the image is cut into this many square cells along its longer
    side, and each cell inside the lens keeps its share of ``max_corners``."""
    descriptor_size_deg: float = degrees_on_default_lens(31.0)
    """Methods on FAST corners: side of the window the binary descriptor samples, degrees;
    31 px (ORB's) on the default lens, 10.2 degrees."""
    max_hamming_fraction: float = 0.25
    """Bit-string methods: a match differs in at most this fraction of its bits (similarity
    1 - 2 d / bits >= 0.5 at the default), in (0, 0.5]."""

    def __post_init__(self) -> None:
        require(self.method in FRONT_END_METHODS,
                f"method must be one of {', '.join(FRONT_END_METHODS)}, got {self.method!r}")
        require(self.max_corners >= 1, f"max_corners must be >= 1, got {self.max_corners}")
        require(
            0 < self.quality_level < 1, f"quality_level must be in (0, 1), got {self.quality_level}"
        )
        require(self.min_distance_deg >= 0,
                f"min_distance_deg must be >= 0, got {self.min_distance_deg}")
        require(
            self.block_size_px >= 3 and self.block_size_px % 2 == 1,
            f"block_size_px must be odd and >= 3, got {self.block_size_px}",
        )
        require(0 < self.harris_k < 0.25, f"harris_k must be in (0, 0.25), got {self.harris_k}")
        require(0 < self.patch_size_deg <= 30,
                f"patch_size_deg must be in (0, 30], got {self.patch_size_deg}")
        require(
            self.subpixel_half_window_px >= 0,
            f"subpixel_half_window_px must be >= 0, got {self.subpixel_half_window_px}",
        )
        require(1 <= self.fast_threshold <= 254,
                f"fast_threshold must be in [1, 254], got {self.fast_threshold}")
        require(1 <= self.fast_threshold_low <= 254,
                f"fast_threshold_low must be in [1, 254], got {self.fast_threshold_low}")
        require(self.grid_cells >= 1, f"grid_cells must be >= 1, got {self.grid_cells}")
        require(0 < self.max_hamming_fraction <= 0.5,
                f"max_hamming_fraction must be in (0, 0.5], got {self.max_hamming_fraction}")
        require(0 < self.descriptor_size_deg <= 60,
                f"descriptor_size_deg must be in (0, 60], got {self.descriptor_size_deg}")



@dataclass(frozen=True, slots=True)
class MatchConfig:
    """ZNCC matching in a search window with the unicity (mutual best) constraint.

    The paper gives no numbers; the defaults are the reference benchmark's window
    and a threshold measured on synthetic pairs (``robot/vision/bench_features.py``).
    """

    search_radius_deg: float | None = degrees_on_default_lens(40.0)
    """Candidates lie within this angle of the point's bearing (turned by a predicted
    rotation, if any), degrees; 40 px on the default lens, 13.2 degrees; None searches the
    whole sphere (code only: TOML cannot write None, so a file can only set a finite
    radius)."""
    min_zncc: float = 0.8
    """Reject matches whose similarity is below this, in [-1, 1]: the ZNCC score of
    ``harris-zncc``, the cosine of SIFT's rows. Bit strings use ``[features]
    max_hamming_fraction`` instead."""
    max_distance_ratio: float | None = None
    """Lowe's ratio test on descriptor distances, in (0, 1]; None = off."""
    ratio_exclusion_deg: float = 1.5
    """The ratio test's second best lies farther than this from the best, degrees: a
    corner's own neighbours are not its rivals (robot.vision.matching)."""

    def __post_init__(self) -> None:
        require(
            self.search_radius_deg is None or 0 < self.search_radius_deg <= 180,
            f"search_radius_deg must be in (0, 180] or None, got {self.search_radius_deg}",
        )
        require(self.ratio_exclusion_deg >= 0,
                f"ratio_exclusion_deg must be >= 0, got {self.ratio_exclusion_deg}")
        require(-1 <= self.min_zncc <= 1, f"min_zncc must be in [-1, 1], got {self.min_zncc}")
        require(
            self.max_distance_ratio is None or 0 < self.max_distance_ratio <= 1,
            f"max_distance_ratio must be in (0, 1] or None, got {self.max_distance_ratio}",
        )



def _tracking_match_config() -> MatchConfig:
    return MatchConfig(search_radius_deg=degrees_on_default_lens(20.0), min_zncc=0.7)


@dataclass(frozen=True, slots=True)
class TeachConfig:
    """Key image selection (Courbon et al. 2008, sec. II-C) and joining new paths to a memory.

    The default M was chosen in the ``lab`` world at the teach driver's default speed,
    when it showed fiducial patches: about two key images per metre on straight
    corridors. In the textured lab it gives 3.5 per metre, 3.7 in the campus (``vmnav
    bench vision``'s ``key_images_per_m``; ``vmnav teach`` prints the spacing).
    """

    min_tracked_points: int = 50
    """M: a key image shares at least this many points tracked from the previous one."""
    min_tracked_fraction: float = 0.35
    """In (0, 1]. A key image with few corners needs only this fraction of them tracked
    (the threshold is min(M, ceil(fraction * corners))): in a sparse scene a fixed M
    would force a key image at every frame. It must stay well below the share of
    the live points a single frame matches, 0.46-0.77 in the ``lab`` and ``campus``
    worlds: at 0.5 the ``campus`` corridor got key images 2 cm apart, too close for a
    key pair (see :mod:`robot.teach`, rule 3)."""
    max_turn_deg: float = 15.0
    """A key image is at most this far turned (odometric yaw) from the previous one, deg:
    the repeat matches the next key image in a window of ``PathStateConfig.matching``'s
    radius (39.6 degrees), so a long
    gap in a turn leaves nothing to match (the ``campus`` U-turn had a 50 deg gap)."""
    max_spacing_m: float = 1.0
    """A key image is at most this far (odometric distance) from the previous one, m: far
    from its key image the repeat's estimate rests on points seen from afar and drifts
    (the open yard of ``building``, seed 2: key images 1.97 m apart on a straight run; 2 m
    before the second the vision said 0.29 m to the left with the robot 3 cm from the
    path, and the filter's gate rejected it until the robot was LOST)."""
    max_missed_frames: int = 2
    """A tracked point survives this many consecutive frames without a match (detector blinks)."""
    tracking: MatchConfig = field(default_factory=_tracking_match_config)
    """Frame-to-frame matching of the tracked points (small window, mutual best)."""
    junction_min_matches: int = 40
    """A path's end joins a key image of another path with at least this many matches
    (two unrelated views share up to about 25 chance matches without a search window)."""
    min_path_length_m: float = 0.2
    """A path taught over the link must span at least this much odometry, m; a shorter
    drive (a teach started and stopped in place) is refused instead of stored."""

    def __post_init__(self) -> None:
        require(self.min_path_length_m >= 0,
                f"min_path_length_m must be >= 0, got {self.min_path_length_m}")
        require(self.max_spacing_m > 0,
                f"max_spacing_m must be > 0, got {self.max_spacing_m}")
        require(
            self.min_tracked_points >= 1,
            f"min_tracked_points must be >= 1, got {self.min_tracked_points}",
        )
        require(
            self.max_missed_frames >= 0,
            f"max_missed_frames must be >= 0, got {self.max_missed_frames}",
        )
        require(0 < self.max_turn_deg <= 180,
                f"max_turn_deg must be in (0, 180], got {self.max_turn_deg}")
        require(
            self.junction_min_matches >= 1,
            f"junction_min_matches must be >= 1, got {self.junction_min_matches}",
        )



#: Models of :class:`RelativePoseConfig`: "planar" (upright planar 2-point), "general"
#: (5-point), "auto" (planar, and 5-point as well when the planar fit looks poor).
RELATIVE_POSE_MODELS = ("planar", "general", "auto")


@dataclass(frozen=True, slots=True)
class RelativePoseConfig:
    """Robust relative pose from unit bearings (reference visual-navigation.md, sec. 4.4).

    RANSAC over minimal solvers (PoseLib's upright planar 2-point, or 5-point),
    scored by the angular Sampson error on the sphere, then refined on the inliers.
    Thresholds are angles: 1 px is about 5.7 mrad on the default 185 degree lens.
    """

    model: str = "auto"
    """One of ``RELATIVE_POSE_MODELS``; the planar model needs level bearings (y vertical)."""
    inlier_threshold_rad: float = 0.012
    """A correspondence is an inlier when its angular Sampson error is below this, rad."""
    huber_scale_rad: float = 0.006
    """Residuals beyond this are down-weighted (Huber loss) in the refinement, rad."""
    confidence: float = 0.999
    """RANSAC stops when an all-inlier sample was drawn with this probability."""
    max_iterations: int = 256
    """Most minimal samples drawn for the planar model."""
    max_iterations_general: int = 1024
    """Most minimal samples drawn for the general (5-point) model."""
    min_inliers: int = 8
    """A fit with fewer inliers is not ok (the planar model has 2 degrees of freedom)."""
    min_planar_inlier_ratio: float = 0.5
    """Model "auto": below this planar inlier ratio the 5-point model is tried too."""
    refine_passes: int = 2
    """Refine on the inliers and re-select them this many times (0: the best RANSAC
    hypothesis, with its inliers)."""

    def __post_init__(self) -> None:
        require(
            self.model in RELATIVE_POSE_MODELS,
            f"model must be one of {', '.join(RELATIVE_POSE_MODELS)}, got {self.model!r}",
        )
        require(
            0 < self.inlier_threshold_rad < 0.5,
            f"inlier_threshold_rad must be in (0, 0.5), got {self.inlier_threshold_rad}",
        )
        require(
            0 < self.huber_scale_rad <= self.inlier_threshold_rad,
            f"huber_scale_rad must be in (0, inlier_threshold_rad], got {self.huber_scale_rad}",
        )
        require(0 < self.confidence < 1, f"confidence must be in (0, 1), got {self.confidence}")
        require(self.max_iterations >= 1, f"max_iterations must be >= 1, got {self.max_iterations}")
        require(
            self.max_iterations_general >= 1,
            f"max_iterations_general must be >= 1, got {self.max_iterations_general}",
        )
        require(self.min_inliers >= 5, f"min_inliers must be >= 5, got {self.min_inliers}")
        require(
            0 <= self.min_planar_inlier_ratio <= 1,
            f"min_planar_inlier_ratio must be in [0, 1], got {self.min_planar_inlier_ratio}",
        )
        require(self.refine_passes >= 0, f"refine_passes must be >= 0, got {self.refine_passes}")



def _state_match_config() -> MatchConfig:
    return MatchConfig(search_radius_deg=degrees_on_default_lens(120.0))


@dataclass(frozen=True, slots=True)
class PathStateConfig:
    """Lateral and angular error from the current view and two key images (DESIGN.md sec. 5.5)."""

    relative_pose: RelativePoseConfig = field(default_factory=RelativePoseConfig)
    """Relative pose of two key images, and of the two-view state (refined)."""
    pose_before_resection: RelativePoseConfig = field(
        default_factory=lambda: RelativePoseConfig(inlier_threshold_rad=0.008,
                                                   huber_scale_rad=0.004, refine_passes=1))
    """Relative pose of the current view and the next key image in the three-view state:
    the planar resection refines it further, so one refinement pass suffices. Its
    tolerance (also the resection's epipolar tolerance) is 0.008 rad (0.46 degree), tighter
    than the key pair's 0.012: where every point is far (the ``campus`` courtyard, 8-13 m)
    a sideways shift of the robot moves the rays by less than 0.012 rad, so at 0.012 a pose
    shifted 20-50 cm sideways and turned a few degrees kept as many inliers as the true one
    (``vmnav bench vision --world campus``: |y| p90 6.6 cm at 0.012 and 0.02, 3.2 cm at
    0.008 and 0.012; the lab 1.9 and 1.7 cm)."""
    min_parallax_deg: float = 2.0
    """Triangulated key-pair points need at least this angle between their two rays, degrees."""
    max_point_distance_m: float = 30.0
    """Triangulated points farther than this from the next key image are dropped, m."""
    point_threshold_rad: float = 0.012
    """A 3D point is an inlier of the current pose when it reprojects within this angle, rad
    (0.69 degree; 0.02 let a far point vote for a pose 20 cm off sideways: see
    ``pose_before_resection``)."""
    min_points: int = 3
    """The three-view state needs at least this many inlier key-pair points in the current
    view (the epipolar matches fix yaw and direction; the points fix the scale, one degree
    of freedom, so 3 leave two for redundancy; measured on simulator frames)."""
    max_odometry_disagreement_deg: float = 15.0
    """A key pair is refused when the visual baseline direction and the teach odometry's
    differ by more than this, degrees."""
    matching: MatchConfig = field(default_factory=_state_match_config)
    """Matching of the current view with the next key image, and of two key images
    (``robot.vision.frame_state``): a window wide enough for a robot 0.5 m and 20 degrees
    off the key image's view (on 234 such views in ``lab``, with the key pairs matched
    directly, a +-40 px window left 26 % without a state, +-120 px 3 %)."""

    def __post_init__(self) -> None:
        require(
            0 <= self.min_parallax_deg < 90,
            f"min_parallax_deg must be in [0, 90), got {self.min_parallax_deg}",
        )
        require(
            self.max_point_distance_m > 0,
            f"max_point_distance_m must be > 0, got {self.max_point_distance_m}",
        )
        require(
            0 < self.point_threshold_rad < 0.5,
            f"point_threshold_rad must be in (0, 0.5), got {self.point_threshold_rad}",
        )
        require(self.min_points >= 2, f"min_points must be >= 2, got {self.min_points}")
        require(
            0 < self.max_odometry_disagreement_deg <= 180,
            f"max_odometry_disagreement_deg must be in (0, 180], got "
            f"{self.max_odometry_disagreement_deg}",
        )



def _localize_match_config() -> MatchConfig:
    return MatchConfig(search_radius_deg=None, min_zncc=0.8)


def _localize_pose_config() -> RelativePoseConfig:
    # 320 samples (10 batches of 32) draw an all-inlier 5-point sample with probability
    # 0.96 at an inlier ratio of 0.4 (1 - (1 - 0.4^5)^320) and 0.999 at 0.6; more only
    # spends time on chance matches (17 ms per candidate at 1024). No refinement: counting
    # inliers needs none, and it halves the time of a true candidate (2 vs 4 ms on 85
    # matches; the same inliers to within one).
    return RelativePoseConfig(model="general", max_iterations_general=320, refine_passes=0)


@dataclass(frozen=True, slots=True)
class LocalizeConfig:
    """Localization of an image in the visual memory (Courbon et al. 2008, sec. II-D).

    A global prefilter ranks every key image by the similarity of patch-normalised
    thumbnails (Milford and Wyeth's SeqSLAM / QVPR teach-and-repeat normalisation),
    then each of the best ``candidates`` is matched and verified geometrically
    (:mod:`robot.memory.verification`): a key image is accepted on the inliers of a
    relative pose that a ground robot can make, never on a raw match count, and the
    accepted key image with the most inliers wins. Defaults measured with
    ``vmnav bench localize`` (true pairs) and ``vmnav bench chance`` (unrelated real images).
    """

    candidates: int = 20
    """Key images verified by full matching, the prefilter's best first."""
    min_inliers: int = 15
    """A key image is accepted with at least this many inliers of the relative pose
    (unrelated real images reach at most 10, ``vmnav bench chance``; true views in the
    ``campus`` world with half the light as few as 17 matches)."""
    min_inlier_ratio: float = 0.35
    """... and at least this share of its matches inliers, in (0, 1]: true views reach
    0.37-0.5 with ORB's whole-image matching in ``campus`` (0.76 and more with Harris +
    ZNCC); unrelated real images, never more than 10 inliers, up to 0.56 with few matches."""
    neighbour_weight: float = 0.0
    """Among the accepted key images the one with the most *path support* wins: its inliers
    plus this times those of its two path neighbours (accepted ones among the candidates).
    A view between key images is seen by several neighbours with nearly equal inliers,
    where far points change little from one key image to the next (the ``campus``
    courtyard: 2 key images off in 8 of 200 queries by inliers alone, 0.96; 0.99 with
    support 0.5); an aliased place elsewhere has no neighbours to support it. 0 (the
    default): inliers alone. Off by default: at 0.5 the demo's repeat relocalized one key
    image behind the robot (the middle of the run that sees it) and went LOST three times
    without progress; the rule must only break near-ties before it can be on."""
    bracket_steps: int = 3
    """The winner is then refined on its path: from it, key images are walked towards the
    side the query lies on (the fitted translation's sign along the key image's forward
    axis), up to this many, until two neighbours bracket the query (one sees it ahead, the
    next behind); the first key image ahead of the query wins, where a route from it
    starts with a target the robot has not passed. Forward views of a far scene give
    nearly equal inliers over several key images: the most inliers alone was 2-3 key
    images off in 5 of 200 ``campus`` views (``vmnav bench vision --world campus``).
    0: the winner as it is."""
    max_yaw_deg: float = 45.0
    """... and the query turned about the vertical by at most this from the key image, deg."""
    max_tilt_deg: float = 10.0
    """... and the vertical axis tilted by at most this between the two views, deg
    (roll and pitch of the robot: a flat floor, or a ramp)."""
    relative_pose: RelativePoseConfig = field(default_factory=_localize_pose_config)
    """The relative pose fitted to the matches (its ``inlier_threshold_rad`` is the
    verification's angular tolerance); the general 5-point model, so that roll and
    pitch are measured rather than assumed."""
    matching: MatchConfig = field(default_factory=_localize_match_config)
    """Full matching of the query against a candidate (no window: the view may have turned)."""
    prefilter_rows_fraction: float = 0.6
    """Thumbnail rows used from the top, fraction in (0, 1]: the floor below the horizon is
    near, bare and changes most with a lateral offset."""
    prefilter_window_px: int = 9
    """Side of the window of the thumbnail's patch normalisation, thumbnail px (odd)."""
    prefilter_max_shift_px: int = 6
    """The query thumbnail is compared shifted sideways by up to this, thumbnail px
    (a turn of the robot shifts the view sideways; 6 px of 80 is about 14 degrees)."""

    def __post_init__(self) -> None:
        require(self.candidates >= 1, f"candidates must be >= 1, got {self.candidates}")
        require(self.min_inliers >= 5, f"min_inliers must be >= 5, got {self.min_inliers}")
        require(self.neighbour_weight >= 0,
                f"neighbour_weight must be >= 0, got {self.neighbour_weight}")
        require(self.bracket_steps >= 0,
                f"bracket_steps must be >= 0, got {self.bracket_steps}")
        require(0 < self.min_inlier_ratio <= 1,
                f"min_inlier_ratio must be in (0, 1], got {self.min_inlier_ratio}")
        require(0 < self.max_yaw_deg <= 180,
                f"max_yaw_deg must be in (0, 180], got {self.max_yaw_deg}")
        require(0 < self.max_tilt_deg <= 180,
                f"max_tilt_deg must be in (0, 180], got {self.max_tilt_deg}")
        require(0 < self.prefilter_rows_fraction <= 1,
                f"prefilter_rows_fraction must be in (0, 1], got {self.prefilter_rows_fraction}")
        require(self.prefilter_window_px >= 3 and self.prefilter_window_px % 2 == 1,
                f"prefilter_window_px must be odd and >= 3, got {self.prefilter_window_px}")
        require(self.prefilter_max_shift_px >= 0,
                f"prefilter_max_shift_px must be >= 0, got {self.prefilter_max_shift_px}")



#: Vision keys that were pixels on the default lens and are angles now (docs/front-end.md):
#: the tables that hold them, the old key, the new one.
RENAMED_VISION_KEYS: tuple[tuple[tuple[str, ...], str, str], ...] = (
    (("features",), "min_distance_px", "min_distance_deg"),
    (("features",), "patch_size_px", "patch_size_deg"),
    (("matching", "teach.tracking", "path_state.matching", "localize.matching"),
     "search_radius_px", "search_radius_deg"),
)
def renamed_vision_key(data: Mapping[str, Any]) -> tuple[str, str] | None:
    """The first pixel-valued vision key ``data`` (a config's tables) still holds, as
    ``(old dotted key, new dotted key)``; None if there is none."""
    for tables, old, new in RENAMED_VISION_KEYS:
        for dotted in tables:
            table = _table(data, dotted)
            if table is not None and old in table:
                return f"{dotted}.{old}", f"{dotted}.{new}"
    return None


def migrate_vision_keys(data: Mapping[str, Any]) -> dict[str, Any]:
    """``data`` with its pixel-valued vision keys turned into the angles they were on the
    default lens (a field log replays with the windows it ran with, on that lens).

    A patch of P px becomes the angle that gives P px again; ``None`` stays ``None``.
    """
    out = copy.deepcopy(dict(data))
    for tables, old, new in RENAMED_VISION_KEYS:
        for dotted in tables:
            table = _table(out, dotted)
            if table is None or old not in table:
                continue
            value = table.pop(old)
            table[new] = None if value is None else degrees_on_default_lens(float(value))
    return out


def _table(data: Mapping[str, Any], dotted: str) -> Any:
    """The (mutable, when ``data`` is) table at ``dotted``, or None."""
    value: Any = data
    for key in dotted.split("."):
        if not isinstance(value, Mapping) or key not in value:
            return None
        value = value[key]
    return value if isinstance(value, dict) else None
