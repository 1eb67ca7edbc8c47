"""The relative pose of two images, each from its own calibrated camera.

What ``vmnav vision pair`` shows and ``vmnav bench real`` measures: the vision front
end (:mod:`robot.vision.front_end`, one per camera: points and descriptors in each
image, bearings through each camera's model, matches between them) and the general
(5-point, 5-dof) relative pose of :func:`robot.vision.epipolar.relative_pose` with its
inlier tolerance an angle on the sphere. Nothing here assumes a ground robot: the two
views may be a stereo rig, two photos, or a key image and a frame.

Convention (OpenCV's stereo calibration, and :class:`~robot.vision.epipolar.EpipolarFit`):
``X_b = R_b_a X_a + t_b_a`` maps a point's coordinates in camera a's frame into camera
b's; ``t_b_a`` is known up to scale (unit length here). For a rig whose cameras have
poses ``T_body_a``, ``T_body_b`` in a body frame (Kalibr's ``T_BS``),
:func:`relative_pose_from_body` gives the reference.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import cv2
import numpy as np
import numpy.typing as npt

from robot.config import FeatureConfig, LocalizeConfig, MatchConfig, RelativePoseConfig
from robot.vision.epipolar import EpipolarFit, relative_pose
from robot.vision.front_end import FrontEnd, make_front_end
from shared.camera_model import CameraModel
from shared.errors import check_shape

FloatArray = npt.NDArray[np.float64]
GreyImage = npt.NDArray[np.uint8]


def _pose_config() -> RelativePoseConfig:
    # 0.15 degrees (2.6 mrad) is about 1 px on a 366 px/rad fisheye; the refinement's
    # Huber scale is half of it.
    threshold = math.radians(0.15)
    return RelativePoseConfig(model="general", inlier_threshold_rad=threshold,
                              huber_scale_rad=threshold / 2, max_iterations_general=2000)


@dataclass(frozen=True, slots=True)
class TwoViewConfig:
    """The front end and the relative pose of two views.

    Attributes:
        matching: matching of the two images; by default localization's (``[localize]
            matching``: the whole image), since the two views, like a query and a key
            image, may differ by any motion.
        relative_pose: the general model, its inlier tolerance an angle, rad.

    The front end's method and parameters (``[features]``) are the cameras'
    (:func:`two_cameras`).
    """

    matching: MatchConfig = field(default_factory=lambda: LocalizeConfig().matching)
    relative_pose: RelativePoseConfig = field(default_factory=_pose_config)


@dataclass(frozen=True, eq=False)
class TwoCameras:
    """The front ends of the two cameras of a pair (built once, reused per pair).

    Attributes:
        front_a: camera a's front end (its lens, mask and method).
        front_b: camera b's, of the same method.
    """

    front_a: FrontEnd
    front_b: FrontEnd


def two_cameras(camera_a: CameraModel, camera_b: CameraModel,
                features: FeatureConfig) -> TwoCameras:
    """The pair's front ends (:func:`robot.vision.front_end.make_front_end`) for ``features``."""
    front_a = make_front_end(features, camera_a)
    front_b = front_a if camera_b is camera_a else make_front_end(features, camera_b)
    return TwoCameras(front_a, front_b)


@dataclass(frozen=True, eq=False)
class TwoView:
    """The front end's output and the relative pose of two views.

    Attributes:
        corners_a: (N, 2) float64 corner pixels of image a, px.
        corners_b: (M, 2) float64 corner pixels of image b, px.
        matched_a: (K, 2) float64 pixels in image a of the matches, px (every point the
            front end describes lies in its lens's image circle, so each has a ray).
        matched_b: (K, 2) float64 the same matches' pixels in image b, px.
        fit: the relative pose (``fit.inlier_mask`` is (K,)); ``fit.ok`` is False when
            there were too few matches or inliers.
    """

    corners_a: FloatArray
    corners_b: FloatArray
    matched_a: FloatArray
    matched_b: FloatArray
    fit: EpipolarFit


def two_view(image_a: GreyImage, image_b: GreyImage, cameras: TwoCameras,
             config: TwoViewConfig, rng: np.random.Generator) -> TwoView:
    """Match two images and fit their relative pose.

    Args:
        image_a: (H_a, W_a) uint8 grey image of camera a (its calibration's size).
        image_b: (H_b, W_b) uint8 grey image of camera b.
        cameras: the two cameras' front ends (:func:`two_cameras`).
        config: matching and pose parameters.
        rng: draws RANSAC's samples.

    Returns:
        Corners, matches and the pose ``X_b = R_b_a X_a + t_b_a``.

    Raises:
        ShapeError: an image is not of its camera's size.
    """
    feats_a = cameras.front_a.describe(image_a)
    feats_b = cameras.front_b.describe(image_b)
    # Camera b's front end: a predicted search would project into b's image.
    matches = cameras.front_b.match(feats_a, feats_b, config.matching)
    pixels_a, pixels_b = matches.pixels_xy(feats_a, feats_b)
    fit = relative_pose(feats_a.bearings[matches.idx_a], feats_b.bearings[matches.idx_b], rng,
                        config.relative_pose)
    return TwoView(feats_a.pixels_xy, feats_b.pixels_xy, pixels_a, pixels_b, fit)


def relative_pose_from_body(T_body_a: FloatArray,
                            T_body_b: FloatArray) -> tuple[FloatArray, FloatArray]:
    """The pose of camera a relative to camera b from their poses in a common body frame.

    ``X_body = T_body_a X_a = T_body_b X_b``, so ``T_b_a = T_body_b^-1 T_body_a``.

    Args:
        T_body_a: (4, 4) float64 rigid transform, camera a -> body (m).
        T_body_b: (4, 4) float64 rigid transform, camera b -> body (m).

    Returns:
        ``(R_b_a, t_b_a)``: (3, 3) rotation and (3,) translation, m, with
        ``X_b = R_b_a X_a + t_b_a``.
    """
    check_shape("T_body_a", np.shape(T_body_a), (4, 4))
    check_shape("T_body_b", np.shape(T_body_b), (4, 4))
    T_b_a = np.linalg.inv(np.asarray(T_body_b, np.float64)) @ np.asarray(T_body_a, np.float64)
    return T_b_a[:3, :3], T_b_a[:3, 3]


def rotation_vector_deg(R: FloatArray) -> FloatArray:
    """(3,) float64 axis times angle of the rotation ``R`` (3, 3), degrees (``cv2.Rodrigues``)."""
    check_shape("R", np.shape(R), (3, 3))
    return np.degrees(cv2.Rodrigues(np.asarray(R, np.float64))[0].ravel())


def rotation_error_deg(R_estimate: FloatArray, R_reference: FloatArray) -> float:
    """The angle of ``R_estimate R_reference^T``, degrees."""
    return float(np.linalg.norm(rotation_vector_deg(R_estimate @ np.asarray(R_reference).T)))


def direction_error_deg(t_estimate: FloatArray, t_reference: FloatArray) -> float:
    """The angle between two translation directions (their lengths do not matter), degrees."""
    a, b = np.asarray(t_estimate, np.float64), np.asarray(t_reference, np.float64)
    cos = float(a @ b / (np.linalg.norm(a) * np.linalg.norm(b)))
    return math.degrees(math.acos(float(np.clip(cos, -1.0, 1.0))))
