// The layer geometry/ (kanesim_geometry): triangle meshes read from files (assimp, loaded
// only when a mesh is read: assimp_module.h), their checks and mass properties, primitive
// shapes, and the motion written as an animated glTF file. Layers above include this header
// or the parts it lists.
#pragma once

#include "geometry/gltf_export.h"      // the motion as an animated glTF 2.0 file
#include "geometry/mass_properties.h"  // mass, centre of mass and inertia of a closed mesh
#include "geometry/mesh_check.h"       // what can be wrong with a mesh file or a mesh
#include "geometry/mesh_load.h"        // reading mesh files
#include "geometry/primitives.h"       // boxes, cylinders, spheres, ... for drawing and tests
#include "geometry/tri_mesh.h"         // triangle meshes, solid and drawn
