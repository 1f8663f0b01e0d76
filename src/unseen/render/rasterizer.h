// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// CPU rasterizer for textured triangle meshes. Written in-project rather than taken from
// a library because it is the tracker's hot path: it must render only inside a region of
// interest, output metric depth and coverage alongside colour, and reuse its buffers so
// that a 2 500-triangle model renders in well under a millisecond on one core.
//
// Conventions: pixel centres at integer coordinates (SPEC 2); a pixel is covered when
// its centre is inside the triangle, with a top-left fill rule so that shared edges are
// covered exactly once. Colour is sampled perspective-correctly (bilinear for textures).
//
// How it works: vertices are moved to the camera frame and projected once; screen
// positions are snapped to 1/256 px so that the edge functions are exact 64-bit
// integers (the fill rule is then exact: no cracks, no double coverage). Triangles
// crossing the near plane z = near_m are clipped in 3-D (Sutherland-Hodgman), as are the
// rare ones projecting far outside the image (a guard band). The z-buffer holds 1/z,
// which is affine in screen space; metric z = 1 / (1/z) is written at the end. Colour is
// deferred: the raster pass stores, per pixel, the winning triangle and its
// perspective-correct barycentric coordinates; a resolve pass then colours each visible
// pixel once. The lens distortion of `camera` is ignored (it is removed at input).
//
// Colour sources, first that applies (per pixel):
//  1. projective textures (Mesh::projectors non-empty): of the projectors that see the
//     point (in front, inside the image, surface facing the projector), the first in the
//     order of how squarely they face the triangle's centre; bilinear, clamped to the
//     image edge. Self-occlusion as seen from the projector is tested against its depth
//     map when it has one (Projector::depth). A point no projector sees falls through to
//     2-4.
//  2. UV texture of the triangle's material (triangles without `triangle_materials` use
//     material 0): uv OBJ style (v up, (0, 0) the bottom-left corner of the image),
//     bilinear, *wrapping* (repeat) outside [0, 1) and across the border, from a mip-map
//     level when the texture is minified (RenderOptions::mipmaps). Not modulated by the
//     diffuse colour.
//  3. per-vertex colours, interpolated perspective-correctly.
//  4. the material's diffuse colour; white when the mesh has no material.
#pragma once

#include <opencv2/core.hpp>

#include "unseen/camera/camera.h"
#include "unseen/geometry/rigid3.h"
#include "unseen/mesh/mesh.h"
#include "unseen/util/thread_pool.h"

namespace unseen {

struct RenderOptions {
  bool cull_back_faces = true;     // drop triangles facing away from the camera
  bool write_color = true;         // false: depth and mask only (faster)
  bool write_triangle_ids = false; // fill RenderBuffers::triangle_id
  bool write_normals = false;      // fill RenderBuffers::normal (for shading; not the tracker)
  // Sample minified UV textures from a mip-map level (render/mipmap.h): one level per
  // material and render, floor(log2(texels per pixel) / 2) over its drawn triangles.
  bool mipmaps = true;
  // Shade a 2x2 block of pixels that one triangle covers whole once, at its centre, and
  // give its four pixels that colour: for a render that is area-averaged to half its
  // resolution afterwards (a supersampled image), where the block becomes one pixel and its
  // four samples would average about that colour. About 4x fewer texture lookups; a UV
  // texture is then sampled from the mip-map level of the block (a large photo texture's
  // lookups miss the cache: the real cube's render 3.4 -> 3.0 ms a frame). Colour only.
  bool shade_quads = false;
  double near_m = 1e-3;            // near clipping distance, metres (> 0)
  // Runs the shading pass's rows on these threads (regions of 8 192 pixels or more); null:
  // on the calling thread. Not owned; must not be running another loop.
  ThreadPool* pool = nullptr;
  void Check() const;
};

// Outputs of one render, all of the size of `roi` (pixel (0, 0) of each buffer is image
// pixel (roi.x0, roi.y0)).
struct RenderBuffers {
  PixelRect roi;
  cv::Mat color;        // CV_32FC3 BGR [0, 1]; zero where not covered
  cv::Mat depth;        // CV_32FC1 camera-frame z, metres; 0 where not covered
  cv::Mat mask;         // CV_8UC1, 255 where covered, 0 elsewhere
  cv::Mat triangle_id;  // CV_32SC1, -1 where not covered (only with write_triangle_ids)
  // CV_32FC3 unit surface normal in the camera frame, as stored in the mesh (outward),
  // interpolated from Mesh::normals or the face normal when the mesh has none; zero where
  // not covered (only with write_normals).
  cv::Mat normal;

  // Internal per-pixel scratch of the raster pass, kept here so that it is reused.
  cv::Mat scratch_ids;      // CV_32SC1 winning triangle
  cv::Mat scratch_weights;  // CV_32FC2 barycentric coordinates (b1, b2) times 1/z
};

// Renders `mesh` seen from `camera` with the object at `cam_from_obj`, restricted to
// `roi` (clipped to the image). Buffers in `out` are reused when their size fits.
// Throws unseen::Error for an invalid mesh/camera; an empty roi gives empty buffers.
// Buffers not asked for by `options` (triangle_id, normal, color) are released.
// Images are limited to 32 768 px per side (fixed-point screen coordinates).
void Render(const Mesh& mesh, const PinholeCamera& camera, const Rigid3d& cam_from_obj,
            const PixelRect& roi, const RenderOptions& options, RenderBuffers* out);

// Builds now what the first Render of `mesh` would otherwise build (the mip-map levels of
// its UV textures, tens of milliseconds for a 2 048 px texture), so that a tracker's first
// frame costs what the others cost. Renders are the same with or without it.
void PrepareForRendering(const Mesh& mesh);

}  // namespace unseen
