// RenderScene's private parts shared by its source files (render_scene.cpp,
// render_lights.cpp, render_probes.cpp): a mesh with its triangle areas, and the Embree
// device and scene. Not part of the installed headers.
#pragma once
#include <embree3/rtcore.h>
#include <string>
#include <vector>
#include "bsdflab/render/scene.h"

namespace bsdflab {

struct RenderScene::Mesh {
    MeshInput in;
    std::vector<double> area; // per triangle
};

struct RenderScene::Embree {
    std::string last_error;
    RTCDevice device = nullptr;
    RTCScene scene = nullptr;
    Embree();
    ~Embree();
};

} // namespace bsdflab
