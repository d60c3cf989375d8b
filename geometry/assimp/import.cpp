// Reading a mesh file with assimp: every mesh of the scene, node transforms applied, merged
// into one indexed triangle list. Welding, scaling and checks happen in kanesim_geometry.
#include <assimp/Importer.hpp>
#include <assimp/config.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include "geometry/assimp/module.h"

namespace kanesim::geometry::assimp_io {
namespace {

// Post-processing. aiProcess_PreTransformVertices applies the node transforms (and merges
// meshes by material); aiProcess_Triangulate splits polygons; aiProcess_SortByPType puts
// points and lines in meshes of their own, whose faces are skipped below (removing them in
// assimp would fail a file of lines only with "No meshes remaining" instead of kanesim's
// "no triangles"). For drawing, aiProcess_GenNormals adds
// flat normals where the file has none, and JoinIdenticalVertices shares vertices after
// texture coordinates and colours are removed (otherwise STL and OBJ corners stay split).
// For a solid, only positions are needed and kanesim welds them itself, across meshes.
unsigned Flags(bool with_normals) {
  unsigned flags = aiProcess_Triangulate | aiProcess_PreTransformVertices | aiProcess_SortByPType;
  if (with_normals) flags |= aiProcess_RemoveComponent | aiProcess_GenNormals | aiProcess_JoinIdenticalVertices;
  return flags;
}

}  // namespace

ImportReply ImportMesh(const ImportRequest& request) {
  ImportReply reply;
  Assimp::Importer importer;
  importer.SetPropertyInteger(AI_CONFIG_PP_RVC_FLAGS, aiComponent_TANGENTS_AND_BITANGENTS | aiComponent_COLORS |
                                                          aiComponent_TEXCOORDS | aiComponent_BONEWEIGHTS |
                                                          aiComponent_ANIMATIONS | aiComponent_TEXTURES |
                                                          aiComponent_LIGHTS | aiComponent_CAMERAS);
  // The file's own axes: Collada's up axis is not turned into Y (its unit is applied).
  importer.SetPropertyBool(AI_CONFIG_IMPORT_COLLADA_IGNORE_UP_DIRECTION, true);
  const aiScene* scene = importer.ReadFile(request.path, Flags(request.with_normals));
  if (!scene) {
    reply.error = importer.GetErrorString();
    if (reply.error.empty()) reply.error = "unknown error";
    return reply;
  }
  size_t n_vertices = 0, n_faces = 0;
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    n_vertices += scene->mMeshes[m]->mNumVertices;
    n_faces += scene->mMeshes[m]->mNumFaces;
  }
  reply.vertices.reserve(n_vertices);
  if (request.with_normals) reply.normals.reserve(n_vertices);
  reply.triangles.reserve(n_faces);
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    const aiMesh& mesh = *scene->mMeshes[m];
    const auto offset = static_cast<uint32_t>(reply.vertices.size());
    for (unsigned v = 0; v < mesh.mNumVertices; ++v) {
      const aiVector3D& p = mesh.mVertices[v];
      reply.vertices.emplace_back(p.x, p.y, p.z);
      if (request.with_normals) {
        const aiVector3D n = mesh.mNormals ? mesh.mNormals[v] : aiVector3D(0, 0, 0);
        reply.normals.emplace_back(n.x, n.y, n.z);
      }
    }
    for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
      const aiFace& face = mesh.mFaces[f];
      if (face.mNumIndices != 3) continue;
      reply.triangles.push_back({offset + face.mIndices[0], offset + face.mIndices[1], offset + face.mIndices[2]});
    }
  }
  reply.ok = true;
  return reply;
}

}  // namespace kanesim::geometry::assimp_io
