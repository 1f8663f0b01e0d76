// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Built-in textured objects for synthetic sequences and tests (SPEC 8), centred on the
// object origin, in metres, UV-textured.
#pragma once

#include <array>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "unseen/mesh/mesh.h"

namespace unseen {

// The thesis's lettered cube: a different letter (A..F) and background colour on each
// face, `texture_px` square texture per face. Faces +x A, -x B, +y C, -y D, +z E, -z F.
Mesh MakeLetteredCube(double edge_m, int texture_px = 256);

// A UV sphere with `rings` x `segments` quads (2 * rings * segments triangles minus the
// poles' degenerate ones) textured by an equirectangular image; empty `texture` makes a
// deterministic globe-like pattern (continents, meridians) so rotation is visible.
Mesh MakeTexturedSphere(double radius_m, int rings = 25, int segments = 50,
                        const cv::Mat& texture = cv::Mat());

// A box of size (x, y, z) metres; one texture per face in the order +x, -x, +y, -y, +z, -z;
// empty entries get a deterministic generated pattern (stripes, text, blobs).
Mesh MakeTexturedBox(const Eigen::Vector3d& size_m,
                     const std::array<cv::Mat, 6>& face_textures = {});

}  // namespace unseen
