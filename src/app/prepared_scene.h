// Scene loading and meshing as both programs do it, with timings and a log summary.
#pragma once

#include <string>
#include <vector>

#include "config.h"
#include "contact.h"
#include "mesh.h"
#include "scene.h"

namespace mpath {

struct PreparedScene {
  Scene scene;
  PatchMesh mesh;
  std::vector<std::string> warnings;
  ContactSplit contacts;  // polygons split where they touch another (mesh.split_contacts)
  double load_seconds = 0;
  double mesh_seconds = 0;
};

PreparedScene prepare_scene(const Options& options);

}  // namespace mpath
