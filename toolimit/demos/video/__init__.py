"""Stage (i) from a video: a camera, 2D endpoint tracks, and their lift to a 3D demonstration.

The camera, tracks and lift need numpy alone, so tracks made by any outside tool can be lifted
without the ``[video]`` extra. Rendering a demonstration to an MP4 (:mod:`.render`) and tracking
its colour markers (:mod:`.marker_tracking`) need OpenCV (``pip install -e ".[video]"``); they are
the only modules of the package that import it.
"""

from toolimit.demos.video.camera import Camera, look_at, read_camera, side_camera, write_camera
from toolimit.demos.video.lift import LiftedDemo, LiftSettings, handle_side, lift_tracks, ray_plane_intersection
from toolimit.demos.video.lifted_file import LiftedRecord, read_lifted, write_lifted
from toolimit.demos.video.tracks import (
    TRACKS_HEADER,
    EndpointTracks,
    perturbed,
    project_demo,
    read_tracks,
    write_tracks,
)

__all__ = [
    "TRACKS_HEADER",
    "Camera",
    "EndpointTracks",
    "LiftSettings",
    "LiftedDemo",
    "LiftedRecord",
    "handle_side",
    "lift_tracks",
    "look_at",
    "perturbed",
    "project_demo",
    "ray_plane_intersection",
    "read_camera",
    "read_lifted",
    "read_tracks",
    "side_camera",
    "write_camera",
    "write_lifted",
    "write_tracks",
]
