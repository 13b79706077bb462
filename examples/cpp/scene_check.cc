// A scene check: is each object {name, K, B} of a haptic scene stable on the
// device? Stable exactly when K lies inside a stable K interval at its B.
// Exit 3 when some object is unstable (as `zwidth check`).
//
//   scene_check MODEL.json SCENE.json DELAY_SAMPLES
//   SCENE.json: {"objects": [{"name": "wall", "K": 20, "B": 0.01}, ...]}
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <string>
#include <vector>

#include <zwidth/io/model_json.h>
#include <zwidth/io/stability_files.h>
#include <zwidth/stability/zwidth.h>

#include "example_main.h"

int main(int argc, char** argv) {
  return RunExample(argc, argv, 4, "MODEL.json SCENE.json DELAY_SAMPLES", [&] {
    zwidth::io::ModelFile model = zwidth::io::ReadModelJson(argv[1]);
    std::string note;
    const double T = zwidth::io::ResolveModelPeriod(std::nullopt, &model, &note);
    const std::vector<zwidth::io::SceneObject> scene = zwidth::io::ReadScene(argv[2]);
    const zwidth::stability::ZWidth z(model.plant, T, std::atoi(argv[3]));
    int unstable = 0;
    for (const zwidth::io::SceneObject& o : scene) {
      const zwidth::io::ObjectVerdict v = zwidth::io::CheckObject(z, o);
      std::printf("%s K %.9g B %.9g: %s (K_cr %.9g)\n", o.name.c_str(), o.K, o.B,
                  v.stable ? "stable" : "unstable", v.critical.K_cr);
      unstable += v.stable ? 0 : 1;
    }
    return unstable > 0 ? 3 : 0;
  });
}
