// What a mesh file declares, checked against its size and MeshLimits before assimp reads it.
//
// assimp sizes its arrays by the counts a file's header declares: a 167-byte PLY that claims
// 10⁸ vertices made it allocate for 10⁸ vertices (minutes, tens of GB) before it found one
// data line. Every format whose header carries counts is checked here, from the header alone:
//
//   PLY (ascii, binary_little_endian, binary_big_endian): every element's count against the
//       limits (vertex ≤ max_vertices, face ≤ max_triangles, any other element ≤ the larger),
//       then the fewest bytes those elements can take against the bytes after end_header:
//         ascii:  2 bytes per property value ("0 "), a list at least its count ("0 ")      (1)
//         binary: the sizes of the scalar properties and of each list's count             (2)
//   binary STL: 84 + 50 n bytes for n declared triangles, exactly (n ≤ max_triangles);
//       assimp compares the size in 32 bits, so a count of 2³¹ + n passed its test.
//   glTF (.gltf JSON, .glb): buffers, buffer views and accessors (mesh_gltf_header.cpp).
//   OFF: its counts against the limits, and the whole file against them (each vertex line 3
//       numbers, each face line "k i_1 ... i_k" with indices below nv): assimp allocates by
//       the face count and aborts the process when fewer faces follow.
//
// OBJ, ASCII STL and the other text formats declare nothing that assimp allocates ahead of
// the data: their size bounds their content.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "geometry/mesh_check.h"
#include "geometry/mesh_load.h"

namespace kanesim::geometry {

// `head`: the file's first bytes (up to kHeaderBytes; the whole file when it is shorter),
// `file_bytes` its size. Appends a problem and returns false when the declared counts
// exceed the limits (kTooLarge) or need more bytes than the file has (kDeclaredBeyondFile).
bool CheckDeclaredSizes(const std::string& path, const std::string& head, uint64_t file_bytes,
                        const MeshLimits& limits, std::vector<MeshProblem>& problems);

// How much of a file CheckDeclaredSizes needs: a PLY header longer than this is refused.
inline constexpr uint64_t kHeaderBytes = 64 * 1024;

// glTF: the JSON's declared sizes (mesh_gltf_header.cpp). `json` is the .gltf file or the
// JSON chunk of a .glb; `bin_bytes` the size of the .glb's BIN chunk (-1: none);
// external buffers are looked up beside `path`.
bool CheckGltfDeclaredSizes(const std::string& path, const std::string& json, int64_t bin_bytes,
                            const MeshLimits& limits, std::vector<MeshProblem>& problems);

}  // namespace kanesim::geometry
