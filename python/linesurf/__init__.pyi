# Type stub of the linesurf Python module (editors complete the API from it).
from types import SimpleNamespace
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

__version__: str

ArrayLike = npt.ArrayLike
PointsLike = Union["Model", npt.ArrayLike]
ImageLike = Union[str, npt.ArrayLike]

class FileFormatError(OSError):
    """A malformed or unreadable input file; the message is the CLI's 'PATH: WHERE: WHAT'."""

class Model:
    """A hybrid point + line-segment model (thesis §3); a point cloud has no segments."""
    def __init__(
        self,
        *,
        points: Optional[ArrayLike] = None,
        normals: Optional[ArrayLike] = None,
        colors: Optional[ArrayLike] = None,
        radii: Optional[ArrayLike] = None,
        segments: Optional[ArrayLike] = None,
        segment_normals: Optional[ArrayLike] = None,
        segment_colors: Optional[ArrayLike] = None,
        segment_radii: Optional[ArrayLike] = None,
        segment_uv: Optional[ArrayLike] = None,
        segment_endpoint_normals: Optional[ArrayLike] = None,
    ) -> None: ...
    def __len__(self) -> int: ...
    def copy(self) -> "Model": ...
    points: npt.NDArray[np.float32]
    normals: Optional[npt.NDArray[np.float32]]
    colors: Optional[npt.NDArray[np.float32]]
    radii: Optional[npt.NDArray[np.float32]]
    segments: npt.NDArray[np.float32]
    segment_normals: Optional[npt.NDArray[np.float32]]
    segment_colors: Optional[npt.NDArray[np.float32]]
    segment_radii: Optional[npt.NDArray[np.float32]]
    segment_uv: Optional[npt.NDArray[np.float32]]
    segment_endpoint_normals: Optional[npt.NDArray[np.float32]]
    @property
    def provenance(self) -> List[npt.NDArray[np.int64]]: ...
    @property
    def point_properties(self) -> Dict[str, npt.NDArray[np.float32]]: ...
    comments: List[str]

class Mesh:
    """A triangle mesh (input of the §3.3 contour extraction)."""
    def __init__(self, vertices: ArrayLike, faces: ArrayLike, *, normals: Optional[ArrayLike] = None,
                 colors: Optional[ArrayLike] = None) -> None: ...
    @property
    def vertices(self) -> npt.NDArray[np.float32]: ...
    @property
    def faces(self) -> npt.NDArray[np.int64]: ...
    @property
    def normals(self) -> Optional[npt.NDArray[np.float32]]: ...
    @property
    def colors(self) -> Optional[npt.NDArray[np.float32]]: ...
    @property
    def uv(self) -> Optional[npt.NDArray[np.float32]]: ...

def read(path: str) -> Model: ...
def read_mesh(path: str) -> Mesh: ...
def write(path: str, model: Union[Model, Mesh, ArrayLike], *, ascii: bool = False) -> None: ...

def geometry(model: PointsLike, *, k: int = 12, recompute_normals: bool = False, orient_normals: bool = True,
             orientation_penalty: float = 0.5, delaunay_neighbours: bool = False, curvature: bool = False,
             curvature_fit: str = "taubin") -> SimpleNamespace: ...
def normals(points: PointsLike, *, k: int = 12, recompute_normals: bool = False, orient_normals: bool = True,
            orientation_penalty: float = 0.5) -> npt.NDArray[np.float32]: ...
def neighbours(points: PointsLike, k: int = 12) -> Tuple[npt.NDArray[np.int64], npt.NDArray[np.float32]]: ...
def curvature(points: PointsLike, k: int = 12, curvature_fit: str = "taubin", **options: Any) -> Tuple[
    npt.NDArray[np.float32], npt.NDArray[np.float32], npt.NDArray[np.float32], npt.NDArray[np.float32]]: ...
def spacing(points: PointsLike, k: int = 12) -> Tuple[npt.NDArray[np.float32], float]: ...
def prepare(model: PointsLike, *, k: int = 12, radius_scale: float = 1.0) -> Model: ...

def extract_eps_delta(cloud: PointsLike, *, epsilon: float = 0.0, epsilon_relative: float = 0.05,
                      delta: float = 0.004, min_replaced: int = 4, max_replaced: int = 0, provenance: bool = False,
                      k: int = 12, recompute_normals: bool = False,
                      orientation_penalty: float = 0.5) -> SimpleNamespace: ...
def extract_shape_approx(cloud: PointsLike, *, method: str = "greedy", delta_n: float = 0.008, seed: int = 1,
                         max_iterations: int = 16, radius_scale: float = 1.0, min_cluster_size: int = 4,
                         min_run_points: int = 4, provenance: bool = False, curvature: bool = True, k: int = 12,
                         recompute_normals: bool = False, orientation_penalty: float = 0.5) -> SimpleNamespace: ...
def extract_contour(mesh: Mesh, *, spacing: float = 0.0, spacing_scale: float = 1.0, seed: int = 1,
                    radius_scale: float = 0.55, points_below: float = 0.0, all_points: bool = False,
                    vertex_normals: bool = False, family_switch_sine: float = 1.0,
                    endpoint_normals: bool = True, merge_normal_deviation: float = 0.01,
                    merge_tangent_deviation: float = 0.05, merge_angle: float = 2.0,
                    merge_max_pieces: int = 32, diagonal_divisions: float = 200.0,
                    merge_strip_angle: float = 4.0) -> SimpleNamespace: ...
def verify(cloud: PointsLike, hybrid: Model, *, epsilon: Optional[float] = None, delta: Optional[float] = None,
           k: Optional[int] = None) -> Dict[str, Any]: ...

def render(model: PointsLike, *, size: Tuple[int, int] = (512, 512), azimuth: float = 30.0, elevation: float = 20.0,
           distance: float = 0.0, zoom: float = 1.0, fov: float = 30.0, up_axis: str = "y",
           eye: Optional[Sequence[float]] = None, target: Optional[Sequence[float]] = None,
           up: Optional[Sequence[float]] = None, prefilter_variance: float = 0.25, cutoff_radius: float = 2.0,
           reconstruction_scale: float = 0.5, radius_scale: float = 1.0, layers: int = 4,
           z_threshold_mode: str = "primitive", z_threshold: Optional[float] = None, alpha_override: float = -1.0,
           backface_culling: bool = True, ambient: float = 0.25, diffuse: float = 0.75, specular: float = 0.2,
           shininess: float = 24.0, light: Optional[Sequence[float]] = None, world_light: bool = False,
           default_color: Optional[Sequence[float]] = None, per_pixel_lighting: bool = False,
           background: Union[str, Sequence[float]] = "white", segment_method: str = "screen",
           segment_lod: float = 0.0, coverage_gain: float = 0.0, coverage_reach: int = 2, tail_coverage: float = 0.0, k: int = 12, tile_size: int = 64, depth: bool = False, alpha: bool = False,
           normal: bool = False) -> Union[npt.NDArray[np.uint8], Dict[str, npt.NDArray[Any]]]: ...

def compare(a: ImageLike, b: ImageLike) -> Dict[str, float]: ...
def difference_heatmap(a: ImageLike, b: ImageLike, *, saturate: float = 32.0) -> npt.NDArray[np.uint8]: ...
def read_image(path: str) -> npt.NDArray[np.uint8]: ...
def write_png(path: str, image: ArrayLike) -> None: ...
def set_threads(threads: int) -> None: ...
def thread_count() -> int: ...
