// The two functions of the assimp module (import.cpp, export.cpp).
#pragma once

#include "geometry/assimp_module.h"

namespace kanesim::geometry::assimp_io {

ImportReply ImportMesh(const ImportRequest& request);
ExportReply ExportScene(const ExportRequest& request);

}  // namespace kanesim::geometry::assimp_io
