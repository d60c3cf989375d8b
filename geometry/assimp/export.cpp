// Writing an animation through assimp's glTF 2.0 exporter.
//
// Scene: root (identity) → world node (static rotation q_GW, Y up) → one node per body
// (identity base transform, one mesh, animated). assimp 5.2's exporter needs, and
// gltf_export.cpp guarantees: unique node names that no internal id can take (prefixed), a
// non-zero mTicksPerSecond (1: keys are in seconds), animated nodes at identity (a node whose
// own transform is a translation of exactly (1, 1, 1) loses it), and no animation on a root
// with a non-identity transform.
#include <assimp/Exporter.hpp>
#include <assimp/material.h>
#include <assimp/scene.h>

#include <memory>

#include "geometry/assimp/module.h"

namespace kanesim::geometry::assimp_io {
namespace {

aiMesh* MakeMesh(const ExportBody& body, unsigned material) {
  auto* mesh = new aiMesh;
  mesh->mName = aiString("mesh_" + body.node_name);
  mesh->mPrimitiveTypes = aiPrimitiveType_TRIANGLE;
  mesh->mMaterialIndex = material;
  const VisualMesh& m = body.mesh;
  mesh->mNumVertices = static_cast<unsigned>(m.vertices.size());
  mesh->mVertices = new aiVector3D[m.vertices.size()];
  mesh->mNormals = new aiVector3D[m.vertices.size()];
  for (size_t i = 0; i < m.vertices.size(); ++i) {
    mesh->mVertices[i] = aiVector3D(float(m.vertices[i].x()), float(m.vertices[i].y()), float(m.vertices[i].z()));
    mesh->mNormals[i] = aiVector3D(float(m.normals[i].x()), float(m.normals[i].y()), float(m.normals[i].z()));
  }
  mesh->mNumFaces = static_cast<unsigned>(m.triangles.size());
  mesh->mFaces = new aiFace[m.triangles.size()];
  for (size_t f = 0; f < m.triangles.size(); ++f) {
    aiFace& face = mesh->mFaces[f];
    face.mNumIndices = 3;
    face.mIndices = new unsigned[3]{m.triangles[f][0], m.triangles[f][1], m.triangles[f][2]};
  }
  return mesh;
}

aiMaterial* MakeMaterial(const ExportBody& body) {
  auto* mat = new aiMaterial;
  const aiString name(body.material_name);
  mat->AddProperty(&name, AI_MATKEY_NAME);
  const aiColor4D rgba(body.rgba[0], body.rgba[1], body.rgba[2], body.rgba[3]);
  mat->AddProperty(&rgba, 1, AI_MATKEY_BASE_COLOR);
  mat->AddProperty(&rgba, 1, AI_MATKEY_COLOR_DIFFUSE);
  const float metallic = 0.0f, roughness = 0.6f;
  mat->AddProperty(&metallic, 1, AI_MATKEY_METALLIC_FACTOR);
  mat->AddProperty(&roughness, 1, AI_MATKEY_ROUGHNESS_FACTOR);
  return mat;
}

aiNodeAnim* MakeChannel(const ExportBody& body, const std::vector<double>& times) {
  auto* channel = new aiNodeAnim;
  channel->mNodeName = aiString(body.node_name);
  const auto n = static_cast<unsigned>(times.size());
  channel->mNumPositionKeys = n;
  channel->mPositionKeys = new aiVectorKey[n];
  channel->mNumRotationKeys = n;
  channel->mRotationKeys = new aiQuatKey[n];
  for (unsigned k = 0; k < n; ++k) {
    const Vec3& p = body.positions[k];
    const auto& q = body.rotations[k];
    channel->mPositionKeys[k] = aiVectorKey(times[k], aiVector3D(float(p.x()), float(p.y()), float(p.z())));
    channel->mRotationKeys[k] = aiQuatKey(times[k], aiQuaternion(float(q[0]), float(q[1]), float(q[2]), float(q[3])));
  }
  return channel;
}

// The whole scene; aiScene's destructor frees every part.
std::unique_ptr<aiScene> MakeScene(const ExportRequest& r) {
  auto scene = std::make_unique<aiScene>();
  const auto nb = static_cast<unsigned>(r.bodies.size());
  scene->mRootNode = new aiNode(r.root_name);
  auto* world = new aiNode(r.world_name);
  world->mTransformation =
      aiMatrix4x4(aiQuaternion(float(r.q_GW[0]), float(r.q_GW[1]), float(r.q_GW[2]), float(r.q_GW[3])).GetMatrix());
  scene->mRootNode->addChildren(1, &world);

  scene->mNumMaterials = nb;
  scene->mMaterials = new aiMaterial*[nb];
  scene->mMeshes = new aiMesh*[nb];
  std::vector<aiNode*> nodes;
  for (unsigned b = 0; b < nb; ++b) {
    const ExportBody& body = r.bodies[b];
    scene->mMaterials[b] = MakeMaterial(body);
    auto* node = new aiNode(body.node_name);
    if (!body.mesh.triangles.empty()) {
      const unsigned index = scene->mNumMeshes++;
      scene->mMeshes[index] = MakeMesh(body, b);
      node->mNumMeshes = 1;
      node->mMeshes = new unsigned[1]{index};
    }
    nodes.push_back(node);
  }
  if (nb > 0) world->addChildren(nb, nodes.data());

  auto* anim = new aiAnimation;
  anim->mName = aiString(r.animation_name);
  anim->mTicksPerSecond = 1.0;  // keys in seconds; 0 would write NaN times
  anim->mDuration = r.times.empty() ? 0.0 : r.times.back();
  anim->mNumChannels = nb;
  anim->mChannels = new aiNodeAnim*[nb];
  for (unsigned b = 0; b < nb; ++b) anim->mChannels[b] = MakeChannel(r.bodies[b], r.times);
  scene->mNumAnimations = 1;
  scene->mAnimations = new aiAnimation*[1]{anim};
  return scene;
}

}  // namespace

ExportReply ExportScene(const ExportRequest& request) {
  ExportReply reply;
  const std::unique_ptr<aiScene> scene = MakeScene(request);
  Assimp::Exporter exporter;
  if (exporter.Export(scene.get(), request.format.c_str(), request.path.c_str()) != AI_SUCCESS) {
    reply.error = exporter.GetErrorString();
    if (reply.error.empty()) reply.error = "unknown error";
    return reply;
  }
  reply.ok = true;
  return reply;
}

}  // namespace kanesim::geometry::assimp_io
