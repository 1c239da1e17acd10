# Type stub of the linesurf Python module (editors complete the API from it). The keywords of
# render, prepare and the extract_* functions are the option tables' fields; their defaults are
# the library's (see inspect.signature) and written here as `...`, never restated;
# tests/python/test_options.py checks that these lists match.
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
    @property
    def segment_properties(self) -> Dict[str, npt.NDArray[np.float32]]: ...
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
             orientation_penalty: float = 0.5, orient: str = "auto", viewpoint: Sequence[float] = (0, 0, 0),
             delaunay_neighbours: bool = False, curvature: bool = False,
             curvature_fit: str = "taubin") -> SimpleNamespace: ...
def normals(points: PointsLike, *, k: int = 12, recompute_normals: bool = False, orient_normals: bool = True,
            orientation_penalty: float = 0.5, orient: str = "auto",
            viewpoint: Sequence[float] = (0, 0, 0)) -> npt.NDArray[np.float32]: ...
def estimate_noise(model: PointsLike, *, samples: int = 2048, max_neighbours: int = 768,
                   footprint: float = 4.0) -> SimpleNamespace: ...
def mls_project(model: Union[Model, ArrayLike], points: ArrayLike, *, support_scale: float = 3.0,
                curvature: bool = False, robust: bool = False) -> SimpleNamespace: ...
def mesh(model: Union[Model, ArrayLike], *, cell_scale: float = ..., support_scale: float = ...,
         min_weight: float = ..., project: bool = ..., robust: bool = ..., max_mb: float = ...) -> Tuple[npt.NDArray[np.float32], npt.NDArray[np.int64]]: ...
def neighbours(points: PointsLike, k: int = 12) -> Tuple[npt.NDArray[np.int64], npt.NDArray[np.float32]]: ...
def curvature(points: PointsLike, k: int = 12, curvature_fit: str = "taubin", **options: Any) -> Tuple[
    npt.NDArray[np.float32], npt.NDArray[np.float32], npt.NDArray[np.float32], npt.NDArray[np.float32]]: ...
def spacing(points: PointsLike, k: int = 12) -> Tuple[npt.NDArray[np.float32], float]: ...
def prepare(
    model: PointsLike,
    *,
    k: int = ...,
    radius_scale: float = ...,
) -> Model: ...

def extract_eps_delta(
    cloud: PointsLike,
    *,
    epsilon: float = ...,
    epsilon_relative: float = ...,
    epsilon_noise: float = ...,
    delta: float = ...,
    min_replaced: int = ...,
    max_replaced: int = ...,
    provenance: bool = ...,
    endpoint_normals: bool = ...,
    k: int = ...,
    recompute_normals: bool = ...,
    orientation_penalty: float = ...,
    orient: str = ...,
    viewpoint: Sequence[float] = ...,
) -> SimpleNamespace: ...
def extract_shape_approx(
    cloud: PointsLike,
    *,
    method: str = ...,
    delta_n: float = ...,
    seed: int = ...,
    max_iterations: int = ...,
    radius_scale: float = ...,
    min_cluster_size: int = ...,
    min_run_points: int = ...,
    curvature_switch_degrees: float = ...,
    curvature_coherence: float = ...,
    provenance: bool = ...,
    endpoint_normals: bool = ...,
    k: int = ...,
    recompute_normals: bool = ...,
    orientation_penalty: float = ...,
    orient: str = ...,
    viewpoint: Sequence[float] = ...,
    curvature: bool = ...,
) -> SimpleNamespace: ...
def extract_curvature_lines(
    cloud: PointsLike,
    *,
    epsilon: float = ...,
    epsilon_relative: float = ...,
    delta: float = ...,
    family: str = ...,
    separation: float = ...,
    min_separation: float = ...,
    width_scale: float = ...,
    step: float = ...,
    min_length: float = ...,
    smoothing_iterations: int = ...,
    field_data_weight: float = ...,
    support_scale: float = ...,
    provenance: bool = ...,
    k: int = ...,
    recompute_normals: bool = ...,
    orientation_penalty: float = ...,
    orient: str = ...,
    viewpoint: Sequence[float] = ...,
) -> SimpleNamespace: ...
def extract_features(
    cloud: PointsLike,
    *,
    angle: float = ...,
    link_radius: float = ...,
    min_length: float = ...,
    tolerance: float = ...,
    robust_normals: bool = ...,
    support_scale: float = ...,
    k: int = ...,
    recompute_normals: bool = ...,
    orientation_penalty: float = ...,
    orient: str = ...,
    viewpoint: Sequence[float] = ...,
) -> SimpleNamespace: ...
def extract_contour(
    mesh: Mesh,
    *,
    spacing: float = ...,
    spacing_scale: float = ...,
    diagonal_divisions: float = ...,
    seed: int = ...,
    family_switch_sine: float = ...,
    radius_scale: float = ...,
    vertex_normals: bool = ...,
    endpoint_normals: bool = ...,
    shading_normals: bool = ...,
    point_masses: bool = ...,
    merge_normal_deviation: float = ...,
    merge_tangent_deviation: float = ...,
    merge_angle: float = ...,
    merge_strip_angle: float = ...,
    merge_max_pieces: int = ...,
    points_below: float = ...,
    all_points: bool = ...,
) -> SimpleNamespace: ...
def verify(cloud: PointsLike, hybrid: Model, *, epsilon: Optional[float] = None, delta: Optional[float] = None,
           k: Optional[int] = None, surface_error: bool = True) -> Dict[str, Any]: ...
def surface_error(reference: Union[Mesh, PointsLike], model: Model, *, samples: int = ...,
                  support_scale: float = ...) -> Dict[str, Any]: ...

def render(
    model: Union[PointsLike, str],
    *,
    size: Tuple[int, int] = ...,
    azimuth: float = ...,
    elevation: float = ...,
    distance: float = ...,
    zoom: float = ...,
    fov: float = ...,
    up_axis: str = ...,
    eye: Optional[Sequence[float]] = ...,
    target: Optional[Sequence[float]] = ...,
    up: Optional[Sequence[float]] = ...,
    prefilter_variance: float = ...,
    cutoff_radius: float = ...,
    reconstruction_scale: float = ...,
    coverage_gain: float = ...,
    coverage_reach: int = ...,
    layers: int = ...,
    tail_layers: bool = ...,
    tail_coverage: float = ...,
    z_threshold_mode: str = ...,
    z_threshold: Optional[float] = ...,
    alpha_override: float = ...,
    backface_culling: bool = ...,
    ambient: float = ...,
    diffuse: float = ...,
    specular: float = ...,
    shininess: float = ...,
    light: Sequence[float] = ...,
    light_color: Sequence[float] = ...,
    headlight: bool = ...,
    default_color: Sequence[float] = ...,
    per_pixel_lighting: bool = ...,
    background: Union[str, Sequence[float]] = ...,
    segment_method: str = ...,
    segment_lod: float = ...,
    tile_size: int = ...,
    k: int = ...,
    radius_scale: float = ...,
    style: str = ...,
    stroke_width: float = ...,
    paper: Union[str, Sequence[float]] = ...,
    ink: Union[str, Sequence[float]] = ...,
    tone_levels: int = ...,
    stroke_depth_tolerance: float = ...,
    silhouettes: bool = ...,
    in_between: bool = ...,
    cross_hatch: bool = ...,
    stroke_seed: int = ...,
    depth: bool = ...,
    alpha: bool = ...,
    normal: bool = ...,
    budget: Optional[int] = ...,
) -> Union[npt.NDArray[np.uint8], Dict[str, npt.NDArray[Any]]]: ...
def lod_build(model: PointsLike, path: str, *, leaf_size: int = ..., grid: int = ..., k: int = ...) -> Dict[str, int]: ...

def compare(a: ImageLike, b: ImageLike) -> Dict[str, float]: ...
def difference_heatmap(a: ImageLike, b: ImageLike, *, saturate: float = 32.0) -> npt.NDArray[np.uint8]: ...
def read_image(path: str) -> npt.NDArray[np.uint8]: ...
def write_png(path: str, image: ArrayLike) -> None: ...
def set_threads(threads: int) -> None: ...
def thread_count() -> int: ...
