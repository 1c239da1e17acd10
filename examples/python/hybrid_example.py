"""Point cloud -> (epsilon, delta) hybrid model (thesis §3.1) -> renders of both from one camera
-> image metrics (§7) -> a side-by-side PNG (points | hybrid | difference).

    PYTHONPATH=build/python /usr/bin/python3 examples/python/hybrid_example.py \
        data/igea_points.ply out/example.png
"""
import sys

import numpy as np

import linesurf


def main(cloud_path="data/igea_points.ply", out_path="example.png"):
    cloud = linesurf.read(cloud_path)                      # Model: cloud.points is (N, 3) float32
    cloud.normals = linesurf.normals(cloud, k=12)          # §6.1: PCA + MST orientation
    cloud = linesurf.prepare(cloud)                        # radii from the neighbour spacing

    result = linesurf.extract_eps_delta(cloud, epsilon_relative=0.05, delta=0.004)
    hybrid, stats = result.model, result.stats
    print(f"{stats['input_points']} points -> {stats['kept_points']} points + {stats['segments']} segments "
          f"({100 * stats['data_reduction']:.1f}% data reduction)")

    camera = dict(size=(512, 512), azimuth=30, elevation=20, fov=30)  # the same view for both
    points_img = linesurf.render(cloud, **camera)          # (512, 512, 4) uint8
    hybrid_img = linesurf.render(hybrid, **camera)

    m = linesurf.compare(points_img, hybrid_img)
    print(f"hybrid vs points: mse {m['mse']:.6f}, psnr {m['psnr']:.2f} dB, ssim {m['ssim']:.4f}, "
          f"mean |diff| {m['mean_abs_diff']:.2f} grey levels")

    diff = linesurf.difference_heatmap(points_img, hybrid_img, saturate=32)
    side_by_side = np.concatenate([points_img, hybrid_img, diff], axis=1)
    linesurf.write_png(out_path, side_by_side[..., :3])
    print(f"wrote {out_path} ({side_by_side.shape[1]}x{side_by_side.shape[0]})")


if __name__ == "__main__":
    main(*sys.argv[1:])
