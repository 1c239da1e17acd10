// The C++ side of bench/python_overhead.py: the render call the Python module makes, timed in
// C++ on the same prepared model and camera. Prints the median and minimum milliseconds per frame.
// Usage: linesurf_python_overhead MODEL WIDTH HEIGHT REPEATS
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "linesurf/io/model_io.h"
#include "linesurf/pipeline/render_job.h"
#include "linesurf/render/renderer.h"

int main(int argc, char** argv) {
  using namespace linesurf;
  if (argc != 5) return std::fprintf(stderr, "usage: %s MODEL WIDTH HEIGHT REPEATS\n", argv[0]), 1;
  HybridModel model = readModel(argv[1]);  // igea: ordinary size, identity frame
  prepareForRendering(model);
  ViewOptions view;
  view.width = std::atoi(argv[2]), view.height = std::atoi(argv[3]);
  const int repeats = std::atoi(argv[4]);
  std::vector<double> ms;
  for (int i = 0; i < repeats + 1; ++i) {
    auto t0 = std::chrono::steady_clock::now();
    Renderer renderer(model, RenderOptions{});
    RenderResult r = renderer.render(viewCameras(renderer.sphere(), view).front());
    auto t1 = std::chrono::steady_clock::now();
    if (i > 0) ms.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());  // first run warms up
    if (r.color.width != view.width) return 1;
  }
  std::sort(ms.begin(), ms.end());
  std::printf("{\"median_ms\": %.4f, \"min_ms\": %.4f, \"repeats\": %d}\n", ms[ms.size() / 2], ms.front(), repeats);
  return 0;
}
