// The camera and the path tracer, shared by both backends (camera.rgen: the ray tracing pipeline;
// camera.comp: the compute cell-grid traversal): per pixel, the un-jittered pixel-center ray gives
// label, depth and normal (traced on the first pass of an accumulation, and reused as the first
// camera path's first hit; GpuLayout.h documents the convention), then frame.sampling.y jittered
// camera paths are traced with the shared integrator (PathTracer.h) and added to the pixel's
// accumulated sums; hdr (mean) and color (tone-mapped) are written from the sums.
//
// The includer declares `SvdagPayload payload` (what a closest-hit query fills) and defines, for a
// world ray (unit direction, relative to the scene's reference point) and an interval already
// clipped to the clipping region:
//   void svdagTraceInterval(vec3 origin, vec3 direction, float tmin, float tmax, uint hitGroup,
//                           bool anyHit)
//       the nearest hit into payload, left as a miss where there is none; hitGroup 1: entry
//       only; with anyHit (shadow rays) only whether anything is hit (payload.label != 0)
// and then calls svdagRenderPixel(pixel) for each pixel of the image.
#ifndef SVDAG_RENDER_PATH_TRACE_GLSL
#define SVDAG_RENDER_PATH_TRACE_GLSL

#include "Features.glsl"

// Far end of every ray: beyond any scene, finite so that no inf enters the traversal.
const float RAY_TMAX = 1.0e30;

// Environment tables for Shading.h (set at the start of main()).
SvdagFloats gEnvMarginal;
SvdagFloats gEnvConditional;
SvdagVec4s gEnvTexels;
#define SVDAG_ENV_MARGINAL(i) gEnvMarginal.v[(i)]
#define SVDAG_ENV_CONDITIONAL(i) gEnvConditional.v[(i)]
#define SVDAG_ENV_TEXEL(i) gEnvTexels.v[(i)].xyz
#include "svdag_render/Shading.h"

layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer SvdagMaterials
{
  Material m[];
};
SvdagMaterials gMaterials;

// Whether the first closest-hit query of the current camera path (its camera ray) hit a block.
bool gCameraRayHit;
bool gFirstQuery;

// The first sample of an accumulation goes through the pixel center: its camera ray's hit is the
// pixel's label, depth and normal (writePrimaryOutputs), kept here by traceRay when
// gCapturePrimary is set. The primary rays are no trace of their own: the trace a compiler may
// inline (the compute backend's grid walk) has one site, in the path tracer.
SvdagPayload gPrimaryPayload;
bool gCapturePrimary = false;

// Clipping planes and crop box (Clipping.h, the code the CPU ray caster runs): every ray below
// is clipped to the kept region before it is traced, so cut-away parts are neither seen nor cast
// shadows, and a ray entering the region inside a solid hits the cut face.
#define SVDAG_CLIP_PLANE(i) frame.clipPlanes[(i)]
#include "svdag/Clipping.h"

// Traces the part of [0, tmax] inside the clipping region into payload (a miss where none is).
void traceClipped(vec3 origin, vec3 direction, float tmax, uint hitGroup, bool anyHit)
{
  payload.label = 0u;
  payload.t = SVDAG_DEPTH_MISS;
  payload.normal = vec3(0.0);
  payload.shading = vec4(0.0);
  SvdagClipInterval c;
  c.kept = true;
  c.tmin = 0.0;
  c.tmax = tmax;
  c.enterPlane = -1;
  if (SVDAG_FEATURE_CLIPPING && frame.clipping.x != 0u)
    c = svdagClipInterval(frame.clipping.x, origin, direction, 0.0, tmax);
  if (!c.kept)
    return;
  svdagTraceInterval(origin, direction, c.tmin, c.tmax, hitGroup, anyHit);
  // Inside a solid at the clipped tmin (zero normal, Traversal.h): the cut face of the plane the
  // ray entered the region through, with the region's outward normal, which faces the ray.
  if (!anyHit && payload.label != 0u && c.enterPlane >= 0 && dot(payload.normal, payload.normal) == 0.0)
    payload.normal = -frame.clipPlanes[c.enterPlane].xyz;
}

// The shading normal of the hit in payload (block.rchit); the face normal where it has none (a
// ray that starts inside, whose normal the raygen may set afterwards, e.g. a clipping cut face).
vec3 shadingNormal()
{
  return dot(payload.shading.xyz, payload.shading.xyz) > 0.0 ? payload.shading.xyz : payload.normal;
}

// The hit in payload as the path tracer's PathHit.
PathHit payloadHit()
{
  PathHit h;
  h.hit = payload.label != 0u;
  // Traversal.h reports a ray that starts inside a solid at t = tmin with no entry face (never
  // for entry-only rays).
  h.inside = h.hit && dot(payload.normal, payload.normal) == 0.0;
  h.t = payload.t;
  h.label = h.hit ? payload.label - 1u : 0u;
  h.normal = payload.normal;
  h.shading = shadingNormal();
  h.lift = payload.shading.w;
  return h;
}

// hitGroup 0: the first hit; 1: the entry-only hit group (block.rint with SVDAG_ENTRY_ONLY), for
// a ray continuing through a surface it has just crossed, or a ray (a shadow ray too) starting
// lifted above a smooth-shaded hit, possibly inside a voxel of a touching label: the solid it
// starts in is skipped. Shadow rays (anyHit) only say whether anything is hit.
PathHit traceRay(vec3 origin, vec3 direction, float tmax, uint hitGroup, bool anyHit)
{
  traceClipped(origin, direction, tmax, hitGroup, anyHit);
  if (anyHit)
  {
    PathHit h;
    h.hit = payload.label != 0u;
    h.inside = false;
    h.t = 0.0;
    h.label = 0u;
    h.normal = vec3(0.0);
    h.shading = vec3(0.0);
    h.lift = 0.0;
    return h;
  }
  PathHit h = payloadHit();
  if (gFirstQuery)
  {
    gCameraRayHit = h.hit;
    gFirstQuery = false;
    if (gCapturePrimary)
      gPrimaryPayload = payload;
  }
  return h;
}

Material labelMaterial(uint labelIndex)
{
  return gMaterials.m[min(labelIndex, max(frame.sampling.w, 1u) - 1u)];
}

#define SVDAG_TRACE(hit, o, d, tmax, skipStart, anyHit)                                           \
  hit = traceRay(o, d, tmax, (skipStart) ? 1u : 0u, anyHit)
#define SVDAG_MATERIAL(label) labelMaterial(label)
#include "svdag_render/PathTracer.h"

struct CameraRay
{
  vec3 origin;
  vec3 direction;
  float tmax;
};

// The camera ray through a point of the image (GpuLayout.h's ViewRays convention), ending at the
// far plane and at the pixel's ray limit.
CameraRay cameraRay(vec2 pixelPoint, uint index, uint width, uint height)
{
  float u = 2.0 * pixelPoint.x / float(width) - 1.0;
  float v = 2.0 * pixelPoint.y / float(height) - 1.0;
  CameraRay ray;
  ray.origin = frame.rayOrigin.xyz + u * frame.rayOriginU.xyz + v * frame.rayOriginV.xyz;
  vec3 span = frame.rayDirection.xyz + u * frame.rayDirectionU.xyz + v * frame.rayDirectionV.xyz;
  float spanLength = length(span);
  ray.direction = span / spanLength;
  ray.tmax = frame.rayOrigin.w != 0.0 ? spanLength : RAY_TMAX;
  if (frame.rayLimits.x != 0u || frame.rayLimits.y != 0u)
    ray.tmax = min(ray.tmax, SvdagFloats(frame.rayLimits.xy).v[index]);
  return ray;
}

// The pixel-center ray's label, depth and normal, from its hit in gPrimaryPayload.
void writePrimaryOutputs(uint index, uint width, uint height)
{
  payload = gPrimaryPayload;
  SvdagUintOutput(frame.sceneOutputs.zw).v[index] = payload.label;
  SvdagFloatOutput(frame.outputs.xy).v[index] = payload.label != 0u ? payload.t : SVDAG_DEPTH_MISS;
  SvdagFloatOutput normals = SvdagFloatOutput(frame.outputs.zw);
  // The shading normal, then (from 3 * width * height on) the entry face normal (GpuLayout.h).
  vec3 shading = payload.label != 0u ? shadingNormal() : vec3(0.0);
  normals.v[3u * index + 0u] = shading.x;
  normals.v[3u * index + 1u] = shading.y;
  normals.v[3u * index + 2u] = shading.z;
  uint faces = 3u * width * height;
  normals.v[faces + 3u * index + 0u] = payload.normal.x;
  normals.v[faces + 3u * index + 1u] = payload.normal.y;
  normals.v[faces + 3u * index + 2u] = payload.normal.z;
}

// How many of pixel (x, y)'s coverage rays, in coverageSubPixel's order, are whole camera paths
// (GpuLayout.h); -1 where the pixel is not an edge. Edges are where its pixel-center surface
// (label and entry face, as the first pass of this accumulation wrote them) differs from one of
// its 8 neighbours', which one sample through the center aliases: a label edge (all of its rays),
// a crease (a step within a label whose faces meet concave, where occlusion changes fastest: the
// corner rays), or a convex step (none).
int coveragePathRays(uvec2 pixel, uint width, uint height)
{
  SvdagWords labels = SvdagWords(frame.sceneOutputs.zw);
  SvdagFloats depths = SvdagFloats(frame.outputs.xy);
  SvdagFloats normals = SvdagFloats(frame.outputs.zw);
  uint faces = 3u * width * height; // where the entry face normals start (GpuLayout.h)
  uint i = pixel.x + width * pixel.y;
  uint label = labels.w[i];
  vec3 face = vec3(normals.v[faces + 3u * i], normals.v[faces + 3u * i + 1u],
    normals.v[faces + 3u * i + 2u]);
  bool step = false, crease = false;
  vec3 hit = vec3(0.0);
  for (int dy = -1; dy <= 1; ++dy)
  {
    for (int dx = -1; dx <= 1; ++dx)
    {
      ivec2 q = ivec2(pixel) + ivec2(dx, dy);
      if (q.x < 0 || q.y < 0 || q.x >= int(width) || q.y >= int(height))
        continue;
      uint j = uint(q.x) + width * uint(q.y);
      if (labels.w[j] != label)
        return int(SVDAG_COVERAGE_GRID * SVDAG_COVERAGE_GRID);
      vec3 faceQ = vec3(normals.v[faces + 3u * j], normals.v[faces + 3u * j + 1u],
        normals.v[faces + 3u * j + 2u]);
      if (label == 0u || crease || faceQ == face)
        continue;
      // Concave where either hit lies in front of the other's face plane.
      if (!step)
      {
        CameraRay ray = cameraRay(vec2(pixel) + 0.5, i, width, height);
        hit = ray.origin + depths.v[i] * ray.direction;
      }
      step = true;
      CameraRay rayQ = cameraRay(vec2(q) + 0.5, j, width, height);
      vec3 hitQ = rayQ.origin + depths.v[j] * rayQ.direction;
      crease = dot(face, hitQ - hit) > 0.0 || dot(faceQ, hit - hitQ) > 0.0;
    }
  }
  return crease ? int(SVDAG_COVERAGE_CORNERS) : step ? 0 : -1;
}

// The grid position of an edge pixel's k-th coverage ray: the grid's four corners first, then the
// rest in row order. Where the four corners hit one surface a straight boundary (a half-plane)
// leaves every ray inside their square on that surface too, so they stand for all of them
// (GpuLayout.h, SVDAG_COVERAGE_CORNERS).
uint coverageSubPixel(uint k)
{
  const uint g = SVDAG_COVERAGE_GRID;
  const uint corners[SVDAG_COVERAGE_CORNERS] =
    uint[SVDAG_COVERAGE_CORNERS](0u, g - 1u, g * (g - 1u), g * g - 1u);
  if (k < SVDAG_COVERAGE_CORNERS)
    return corners[k];
  // The rest: g - 2 of the first row, the g - 2 full rows, g - 2 of the last.
  uint j = k - SVDAG_COVERAGE_CORNERS;
  if (j < g - 2u)
    return 1u + j;
  j -= g - 2u;
  if (j < g * (g - 2u))
    return g + j;
  return g * (g - 1u) + 1u + (j - g * (g - 2u));
}

// Whether a pixel's record after its corner rays shows one surface only (all SVDAG_COVERAGE_CORNERS
// of them): its other rays are not traced, and that surface counts for all of them.
bool coverageSettled(uvec4 keys)
{
  return (keys[0] & 0xFFu) == SVDAG_COVERAGE_CORNERS && keys[1] == 0u;
}

// A coverage ray's entry face as its record keeps it (GpuLayout.h; 0 for the background).
uint coverageFaceBits(uint label, vec3 face)
{
  return label != 0u ? svdagPackDirection8(face) << 16u : 0u;
}

// Counts one coverage ray's surface (label index + 1, 0: background; coverageFaceBits) in the
// pixel's record (GpuLayout.h): labels in `labels`, counts and packed faces in `keys`, and the
// ray's radiance and weight (`path`: 1 for a whole path, else all 0) in `paths`.
void countCoverage(inout uvec4 labels, inout uvec4 keys, inout vec4 paths[SVDAG_COVERAGE_SLOTS],
  uint label, uint faceBits, vec4 path)
{
  for (uint k = 0u; k < SVDAG_COVERAGE_SLOTS; ++k)
  {
    if (keys[k] == 0u)
    {
      labels[k] = label;
      keys[k] = faceBits | 1u;
      paths[k] = path;
      return;
    }
    if (labels[k] == label && (keys[k] & 0xFFFF0000u) == faceBits)
    {
      keys[k] += 1u;
      paths[k] += path;
      return;
    }
  }
}

#ifdef SVDAG_COVERAGE_SUBGROUP
// The compute backend shares out a subgroup's coverage rays: its edge pixels are ranked (a
// ballot), every invocation traces rays of the list in turn (ray `slot`: edge pixel slot / R,
// its ray number slot % R, R the rays a pixel traces in this phase), where one invocation per
// edge pixel would keep its SIMD neighbours idle through all of them; after each round every edge
// pixel takes its own rays' hits from the lanes that traced them (shuffles). Two phases: every
// edge pixel's corner rays, then the other rays of the pixels whose corners did not settle them
// (ranked by a second ballot). The rays and the order in which each pixel counts them are those
// of the per-pixel loop, so the records are the same.

// The lane of the subgroup holding the `rank`-th set bit of `ballot` (rank < its bit count).
uint svdagBallotLane(uvec4 ballot, uint rank)
{
  for (uint w = 0u; w < 4u; ++w)
  {
    uint bits = ballot[w];
    uint count = uint(bitCount(bits));
    if (rank < count)
    {
      for (uint k = 0u; k < rank; ++k)
        bits &= bits - 1u;
      return 32u * w + uint(findLSB(bits));
    }
    rank -= count;
  }
  return 0u;
}
#endif

// One pixel of the frame: its primary outputs (on the first pass of an accumulation) and
// frame.sampling.y camera paths added to its sums; or, in the coverage dispatch
// (frame.coverage.z, GpuLayout.h), the hits of its sub-pixel rays if it is on an edge (on a
// label edge with their paths' radiance). Both go through the path tracer's one trace site: a
// coverage ray off label edges is a path that ends at its first hit (no bounces, no next-event
// estimation). With SVDAG_COVERAGE_SUBGROUP every invocation of the subgroup must call this (the
// coverage dispatch shares rays across it).
void svdagRenderPixel(uvec2 pixel)
{
  uint width = frame.image.x;
  uint height = frame.image.y;
  bool coverage = frame.coverage.z != 0u;
  bool inImage = pixel.x < width && pixel.y < height;
  if (!inImage && !coverage)
    return;
  uint index = inImage ? pixel.x + width * pixel.y : 0u;
  uint before = frame.sampling.x;
  uint samples = frame.sampling.y;
  const uint coverageRays = SVDAG_COVERAGE_GRID * SVDAG_COVERAGE_GRID;
  int pathRays = coverage && inImage ? coveragePathRays(pixel, width, height) : -1;
  bool edge = pathRays >= 0;
  uvec4 coveredLabels = uvec4(0u), coveredKeys = uvec4(0u);
  vec4 coveredPaths[SVDAG_COVERAGE_SLOTS];
  for (uint k = 0u; k < SVDAG_COVERAGE_SLOTS; ++k)
    coveredPaths[k] = vec4(0.0);
  // The coverage rays: a pixel's rays in this phase and the number of its first (the corners,
  // then the others); `edge` is whether this pixel traces in the phase.
  uint phaseRays = SVDAG_COVERAGE_CORNERS, phaseFirst = 0u;
#ifdef SVDAG_COVERAGE_SUBGROUP
  uvec4 edges = uvec4(0u);
  uint rays = 0u, edgeRank = 0u, phase = 0u, phaseStart = 0u;
  if (coverage)
  {
    // Subgroup-uniform from here: every lane runs the same rounds.
    edges = subgroupBallot(edge);
    rays = subgroupBallotBitCount(edges) * phaseRays;
    edgeRank = subgroupBallotExclusiveBitCount(edges);
    samples = (rays + gl_SubgroupSize - 1u) / gl_SubgroupSize;
  }
#else
  if (coverage)
    samples = edge ? phaseRays : 0u;
#endif
  bool settled = false;

  gEnvMarginal = SvdagFloats(frame.environmentMap.xy);
  gEnvConditional = SvdagFloats(frame.environmentMap.zw);
  gEnvTexels = SvdagVec4s(frame.environmentMap2.xy);
  gMaterials = SvdagMaterials(frame.materials.xy);
  // A coverage ray off label edges ends at its first hit (no bounces, no next-event estimation).
  uvec4 firstHit = frame.lighting;
  firstHit.zw = uvec2(0u, firstHit.w & ~FLAG_NEE);
  PathTracerParams params =
    PathTracerParams(frame.sunDirection, frame.sunRadiance, frame.environment, frame.lighting);

  vec4 sum = vec4(0.0);
  float squares = 0.0;
  const vec3 luminance = vec3(0.2126, 0.7152, 0.0722);
  for (uint s = 0u; s < samples; ++s)
  {
    // One independent stream per (pixel, global sample index, seed).
    uint rng = pcgHash(index ^ pcgHash((before + s) ^ pcgHash(frame.sampling.z)));
    vec2 jitter = vec2(random01(rng), random01(rng));
    // The pixel the ray goes through: this one, or in the shared coverage, the edge pixel whose
    // ray number `slot` of the subgroup's list this is.
    uint rayIndex = index;
    uint slot = s;
    bool traces = true;
    int rayPathRays = pathRays;
#ifdef SVDAG_COVERAGE_SUBGROUP
    if (coverage)
    {
      slot = (s - phaseStart) * gl_SubgroupSize + gl_SubgroupInvocationID;
      traces = slot < rays;
      uint owner = svdagBallotLane(edges, traces ? slot / phaseRays : 0u);
      rayIndex = subgroupShuffle(index, owner);
      rayPathRays = subgroupShuffle(pathRays, owner);
    }
#endif
    bool wholePath = false;
    if (coverage)
    {
      uint coverageRay = phaseFirst + slot % phaseRays;
      wholePath = int(coverageRay) < rayPathRays;
      uint sub = coverageSubPixel(coverageRay);
      jitter = (vec2(sub % SVDAG_COVERAGE_GRID, sub / SVDAG_COVERAGE_GRID) + 0.5) /
        float(SVDAG_COVERAGE_GRID);
      // A stream of its own per (pixel, sub-pixel, seed), apart from the pixels' samples (its
      // seed hashed differently): a path of its own, not a copy of a sample's.
      rng = pcgHash(rayIndex ^ pcgHash(sub ^ pcgHash(frame.sampling.z ^ 0x9E3779B9u)));
      params.config = wholePath ? frame.lighting : firstHit;
    }
    bool primary = before == 0u && s == 0u && !coverage;
    if (primary)
      jitter = vec2(0.5);
    if (primary || coverage)
    {
      // A miss unless the path's camera ray hits (traceRay).
      gPrimaryPayload.label = 0u;
      gPrimaryPayload.t = SVDAG_DEPTH_MISS;
      gPrimaryPayload.normal = vec3(0.0);
      gPrimaryPayload.shading = vec4(0.0);
    }
    gCapturePrimary = primary || coverage;
    CameraRay ray = cameraRay(vec2(rayIndex % width, rayIndex / width) + jitter, rayIndex, width,
      height);
    gFirstQuery = true;
    gCameraRayHit = false;
    // Bounded so that sums of absurd emissions stay finite (tracePath never returns NaN/Inf).
    vec3 radiance = ray.tmax > 0.0 && traces
      ? min(tracePath(params, ray.origin, ray.direction, ray.tmax, rng), vec3(1.0e30))
      : vec3(0.0);
    gCapturePrimary = false;
    if (coverage)
    {
      uint faceBits = coverageFaceBits(gPrimaryPayload.label, gPrimaryPayload.normal);
      vec4 path = wholePath
        ? vec4(gCameraRayHit ? radiance : frame.background.rgb, 1.0) : vec4(0.0);
#ifdef SVDAG_COVERAGE_SUBGROUP
      // This round's rays, in slot order: each edge pixel counts those of its own.
      for (uint l = 0u; l < gl_SubgroupSize; ++l)
      {
        uint label = subgroupShuffle(gPrimaryPayload.label, l);
        uint face = subgroupShuffle(faceBits, l);
        vec4 lanePath = subgroupShuffle(path, l);
        uint traced = (s - phaseStart) * gl_SubgroupSize + l;
        if (edge && traced < rays && traced / phaseRays == edgeRank)
          countCoverage(coveredLabels, coveredKeys, coveredPaths, label, face, lanePath);
      }
      if (phase == 0u && s + 1u == samples)
      {
        // The corners are in: the pixels they did not settle trace the other rays.
        settled = edge && coverageSettled(coveredKeys);
        edge = edge && !settled;
        phase = 1u;
        phaseFirst = SVDAG_COVERAGE_CORNERS;
        phaseRays = coverageRays - SVDAG_COVERAGE_CORNERS;
        phaseStart = s + 1u;
        edges = subgroupBallot(edge);
        rays = subgroupBallotBitCount(edges) * phaseRays;
        edgeRank = subgroupBallotExclusiveBitCount(edges);
        samples = phaseStart + (rays + gl_SubgroupSize - 1u) / gl_SubgroupSize;
      }
#else
      countCoverage(coveredLabels, coveredKeys, coveredPaths, gPrimaryPayload.label, faceBits,
        path);
      if (s + 1u == SVDAG_COVERAGE_CORNERS)
      {
        // The corners are in: the others unless they settled the pixel (ray s is number s).
        settled = coverageSettled(coveredKeys);
        samples = settled ? samples : coverageRays;
        phaseRays = coverageRays;
      }
#endif
      continue;
    }
    if (primary)
      writePrimaryOutputs(index, width, height);
    vec4 value = gCameraRayHit ? vec4(radiance, 1.0) : frame.background;
    sum += value;
    float y = min(dot(value.rgb, luminance), 1.0e15);
    squares += y * y;
  }
  if (coverage)
  {
    if (!inImage)
      return;
    if (settled)
      coveredKeys[0] += coverageRays - SVDAG_COVERAGE_CORNERS;
    uint record = SVDAG_COVERAGE_RECORD_VEC4S * index;
    SvdagUvec4Output records = SvdagUvec4Output(frame.coverage.xy);
    records.v[record] = coveredLabels;
    records.v[record + 1u] = coveredKeys;
    SvdagVec4Output paths = SvdagVec4Output(frame.coverage.xy);
    for (uint k = 0u; k < SVDAG_COVERAGE_SLOTS; ++k)
      paths.v[record + 2u + k] = coveredPaths[k];
    return;
  }

  SvdagVec4Accumulation accumulation = SvdagVec4Accumulation(frame.materials.zw);
  vec4 total = before == 0u ? sum : accumulation.v[index] + sum;
  accumulation.v[index] = total;
  SvdagFloatAccumulation squareSums = SvdagFloatAccumulation(frame.statistics.xy);
  float totalSquares = before == 0u ? squares : squareSums.v[index] + squares;
  squareSums.v[index] = totalSquares;
  uint n = before + samples;
  float meanLuminance = dot(total.rgb, luminance) / float(max(n, 1u));
  SvdagFloatOutput(frame.statistics.zw).v[index] = n < 2u ? 0.0
    : max(totalSquares / float(n) - meanLuminance * meanLuminance, 0.0) / float(n - 1u);
  vec4 hdr = total / float(max(n, 1u));
  SvdagVec4Output(frame.outputs2.xy).v[index] = hdr;
  SvdagUintOutput(frame.outputs2.zw).v[index] = svdagDisplayColor(hdr, frame.display.x);
}

#endif
