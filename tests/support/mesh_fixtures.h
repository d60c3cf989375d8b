// Mesh files for the tests of the language's mesh functions and MeshBody: written by the
// project's own code (tests/support/mesh_files.h), never downloaded.
#pragma once

#include <string>

namespace kanesim::meshfix {

// A fresh folder under the system temp dir, unique to this process and `name`.
std::string MeshFixtureDir(const std::string& name);

// Writes a mesh of one kind to `path` (the format follows the extension where it matters):
//   box          the solid box 1 × 0.1 × 0.05 m spanning x = 0 .. 1, centred in y and z
//                (the stdlib Box(lx = 1, ly = 0.1, lz = 0.05)), binary STL
//   box_mm       the same in millimetres, binary STL
//   open         the box without its +x face's two triangles: 4 open edges, ASCII STL
//   misoriented  the box with one triangle turned over: 3 edges traversed twice the same way
//   inside_out   the box with every triangle turned over (PLY)
//   flat         a square, both sides: zero volume (OBJ)
//   degenerate   the box plus a triangle with a repeated vertex
//   huge         a sparse file of 257 MiB, over the 256 MiB limit (no disk space used)
//   junk         text that is no mesh format
// False for an unknown kind.
bool WriteMeshFixture(const std::string& path, const std::string& kind);

}  // namespace kanesim::meshfix
