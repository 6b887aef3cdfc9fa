/* Smooth shading normals estimated from the occupancy of the hit label, written once for C++
 * (with GLM) and GLSL 4.60 (the CPU ray caster and the renderer's closest-hit shader run it).
 *
 * Include after Traversal.h (it uses its stream macros, SVDAG_INOUT and svdagLeafBit). The
 * includer also defines how the blocks of the same label in the 3 x 3 x 3 cells around the hit
 * block are found:
 *   SVDAG_NEIGHBOURS_PARAM   leading parameter declaration that carries them (C++:
 *                            "const uint32_t* svdagNeighbours,", 27 root references)
 *   SVDAG_NEIGHBOURS_ARG     the matching argument
 *   SVDAG_NEIGHBOUR_ROOT(n)  the root reference of the label's block in cell offset n =
 *                            (dx + 1) + 3 (dy + 1) + 9 (dz + 1), dx, dy, dz in -1..1 (13: the hit
 *                            block itself), or SVDAG_NO_BLOCK where that cell holds none of the
 *                            label (or lies outside the volume)
 *
 * Estimator: the gradient of the label's occupancy smoothed by the separable kernel
 * w(t) = (1 - t^2 / R^2)^2 for |t| < R, R = SVDAG_SMOOTH_RADIUS = 2.5 voxels, evaluated at a
 * continuous point (not at a voxel center, so the normal varies smoothly across a voxel face):
 * n ~ sum over voxels c of occ(c) * grad w(c - q), which points out of the label. It is evaluated
 * twice: at the hit point p, and at q = p moved along that first estimate onto the smoothed
 * occupancy's 0.5 level (one Newton step), whose normal is the result: hit points on neighbouring
 * steps of the staircase lie up to a voxel apart, and evaluated there the normal field would show
 * the voxel grid as a texture. Why this kernel: it and its derivative vanish at |t| = R, so the
 * estimate is continuous as the point moves and voxels enter and leave the window (a truncated
 * Gaussian jumps there); with R = 2.5 the window is exactly 5 voxel centers per axis, which always
 * lie in 2 leaves per axis, so 8 DAG descents (one 64-bit leaf mask each) give all 125
 * occupancies: 16 descents per hit. On voxelized spheres and tubes of radius 4 to 64 the mean
 * error is about 4 to 5 degrees, the face normal's 28 to 45 (bench/shading.py).
 *
 * Facing: the result is turned towards the viewer (dot(n, -dir) >= SVDAG_SMOOTH_MIN_COS) by
 * adding a multiple of the entry-face normal, so that a silhouette never shades a back side;
 * where the gradient vanishes (a 1-voxel plate seen edge-on, a lone voxel's symmetric
 * neighbourhood) the entry face normal is returned.
 */
#ifndef SVDAG_SMOOTH_NORMAL_H
#define SVDAG_SMOOTH_NORMAL_H

#ifdef __cplusplus
namespace svdag
{
namespace traversal
{
using glm::dot;
using glm::length;
using glm::normalize;
using glm::vec4;
#ifndef SVDAG_NEIGHBOURS_PARAM
#define SVDAG_NEIGHBOURS_PARAM const uint32_t *svdagNeighbours,
#define SVDAG_NEIGHBOURS_ARG svdagNeighbours,
#define SVDAG_NEIGHBOUR_ROOT(n) svdagNeighbours[(n)]
#endif
#endif

/* "No block of this label in that cell": never a valid root reference (the host checks). */
SVDAG_CONST SVDAG_NO_BLOCK = 0xFFFFFFFFu;
#define SVDAG_SMOOTH_RADIUS 2.5f
#define SVDAG_SMOOTH_MIN_COS 0.05f
#define SVDAG_SMOOTH_MAX_LIFT 2.0f
#define SVDAG_SMOOTH_MAX_STEP 1.5f

/* The 4^3 leaf at cell-local leaf corner `leaf` (multiples of 4 in 0..12) of the block with
 * root reference rootRef: the stored mask (complement applied) and in `symmetry` the symmetry
 * under which the child reads it (voxel (x, y, z) at bit leafSymmetryBit(symmetry, x, y, z));
 * empty and full regions expand to all-zero and all-one masks, symmetry 0. */
SVDAG_FN uvec2 svdagLeafMaskAt(SVDAG_STREAMS_PARAM uint rootRef, uint midRefBits,
  uint leafRefBits, uvec3 leaf, SVDAG_INOUT(uint) symmetry)
{
  symmetry = 0u;
  bool inverted = refComplement(rootRef);
  SVDAG_OFFSET_T offset = SVDAG_OFFSET_T(refTarget(rootRef));
  uint header;
  SVDAG_READ_BITS(header, SVDAG_ROOT_STREAM, offset, COMPACT_HEADER_BITS);
  uint o8 = octant(leaf.x, leaf.y, leaf.z, MID_SIZE);
  uint mixed = nodeMixedMask(header);
  if ((mixed & (1u << o8)) == 0u)
    return ((nodeFullMask(header) >> o8) & 1u) != (inverted ? 1u : 0u) ? uvec2(0xFFFFFFFFu)
                                                                      : uvec2(0u);
  offset = svdagRootChildMid(SVDAG_STREAMS_ARG offset, header, childRank(mixed, o8), midRefBits,
    leafRefBits, inverted);
  SVDAG_READ_BITS(header, SVDAG_MID_STREAM, offset, COMPACT_HEADER_BITS);
  uvec3 inMid = leaf % uvec3(MID_SIZE);
  uint o4 = octant(inMid.x, inMid.y, inMid.z, LEAF_SIZE);
  mixed = nodeMixedMask(header);
  if ((mixed & (1u << o4)) == 0u)
    return ((nodeFullMask(header) >> o4) & 1u) != (inverted ? 1u : 0u) ? uvec2(0xFFFFFFFFu)
                                                                      : uvec2(0u);
  uvec2 mask = svdagMidChildLeaf(SVDAG_STREAMS_ARG offset, header, childRank(mixed, o4),
    leafRefBits, symmetry);
  return inverted ? ~mask : mask;
}

/* The kernel w(t) = (1 - t^2/R^2)^2 and its derivative, zero for |t| >= R. */
SVDAG_FN float svdagSmoothWeight(float t)
{
  float q = 1.0f - t * t / (SVDAG_SMOOTH_RADIUS * SVDAG_SMOOTH_RADIUS);
  return q > 0.0f ? q * q : 0.0f;
}
SVDAG_FN float svdagSmoothWeightDerivative(float t)
{
  float q = 1.0f - t * t / (SVDAG_SMOOTH_RADIUS * SVDAG_SMOOTH_RADIUS);
  return q > 0.0f ? -4.0f * t * q / (SVDAG_SMOOTH_RADIUS * SVDAG_SMOOTH_RADIUS) : 0.0f;
}

/* The smoothed occupancy of the label at cell-local point q (-4 <= q <= 20 on each axis): xyz the
 * outward gradient sum over voxels c of occ(c) grad w(c - q) (voxel units), w how far q lies below
 * the 0.5 level, (v - W / 2) / |xyz| with v the kernel-weighted occupancy and W the kernel's sum
 * (0 where the gradient vanishes). */
SVDAG_FN vec4 svdagOccupancyGradient(SVDAG_STREAMS_PARAM SVDAG_NEIGHBOURS_PARAM uint midRefBits,
  uint leafRefBits, vec3 q)
{
  // Per axis: the 5 voxels whose centers can lie within R of q (first one `first`), their
  // weights, and the corner of the first of the 2 leaves that hold them.
  ivec3 first;
  ivec3 leaf0;
  float wx[5];
  float wy[5];
  float wz[5];
  float dx[5];
  float dy[5];
  float dz[5];
  for (int a = 0; a < 3; ++a)
  {
    float c = q[a] < -4.0f ? -4.0f : (q[a] > 20.0f ? 20.0f : q[a]); // no huge float to int
    first[a] = int(SVDAG_FLOOR(c - 2.0f));
    leaf0[a] = first[a] - (first[a] & 3); // floor to a multiple of 4, also below 0
  }
  for (int i = 0; i < 5; ++i)
  {
    float tx = float(first.x + i) + 0.5f - q.x;
    float ty = float(first.y + i) + 0.5f - q.y;
    float tz = float(first.z + i) + 0.5f - q.z;
    wx[i] = svdagSmoothWeight(tx);
    wy[i] = svdagSmoothWeight(ty);
    wz[i] = svdagSmoothWeight(tz);
    dx[i] = svdagSmoothWeightDerivative(tx);
    dy[i] = svdagSmoothWeightDerivative(ty);
    dz[i] = svdagSmoothWeightDerivative(tz);
  }
  // The 2 x 2 x 2 leaves around the window, each from the label's block of its cell.
  uvec2 masks[8];
  uint symmetries[8];
  for (int l = 0; l < 8; ++l)
  {
    ivec3 corner = leaf0 + 4 * ivec3(l & 1, (l >> 1) & 1, (l >> 2) & 1);
    ivec3 cellOffset = ivec3(SVDAG_FLOOR(vec3(corner) / 16.0f));
    uint root = SVDAG_NEIGHBOUR_ROOT(uint(
      (cellOffset.x + 1) + 3 * (cellOffset.y + 1) + 9 * (cellOffset.z + 1)));
    symmetries[l] = 0u;
    masks[l] = root == SVDAG_NO_BLOCK
      ? uvec2(0u)
      : svdagLeafMaskAt(SVDAG_STREAMS_ARG root, midRefBits, leafRefBits,
          uvec3(corner - 16 * cellOffset), symmetries[l]);
  }
  // Separable sums: per row (y, z) the x-sums of w and w', then weighted by the y and z kernels.
  // Occupied voxels behind q make grad w(c - q) point from them towards q: out of the label.
  vec3 g = vec3(0.0f);
  float v = 0.0f;
  for (int k = 0; k < 5; ++k)
  {
    int lz = first.z + k - leaf0.z; // 0..7
    for (int j = 0; j < 5; ++j)
    {
      int ly = first.y + j - leaf0.y;
      float s = 0.0f;
      float sd = 0.0f;
      for (int i = 0; i < 5; ++i)
      {
        int lx = first.x + i - leaf0.x;
        uint m = uint((lx >> 2) + 2 * (ly >> 2) + 4 * (lz >> 2));
        if (svdagLeafBit(masks[m],
              leafSymmetryBit(symmetries[m], uint(lx & 3), uint(ly & 3), uint(lz & 3))))
        {
          s += wx[i];
          sd += dx[i];
        }
      }
      g.x += sd * wy[j] * wz[k];
      g.y += s * dy[j] * wz[k];
      g.z += s * wy[j] * dz[k];
      v += s * wy[j] * wz[k];
    }
  }
  float len = length(g);
  if (!(len > 1.0e-3f)) // no preferred direction (thin or symmetric structure), or NaN
    return vec4(0.0f);
  float sumX = wx[0] + wx[1] + wx[2] + wx[3] + wx[4];
  float sumY = wy[0] + wy[1] + wy[2] + wy[3] + wy[4];
  float sumZ = wz[0] + wz[1] + wz[2] + wz[3] + wz[4];
  return vec4(g, (v - 0.5f * sumX * sumY * sumZ) / len);
}

/* The unit shading normal (xyz; cell-local axes = volume index space axes) at the cell-local hit
 * point p of a voxel-level hit whose entry face is faceNormal, seen along dir, and (w) how far, in
 * voxels, rays that leave the surface should start along it to clear the voxel staircase that the
 * smooth surface stands for: half a voxel plus how far p lies below the smoothed occupancy's 0.5
 * level, at most SVDAG_SMOOTH_MAX_LIFT; 0 with the face normal. (The start may lie inside a voxel
 * of a touching label: the renderer traces those rays so that the solid they start in does not
 * count, PathTracer.h.) A zero faceNormal (the ray started inside) gives zero.
 * The gradient is taken at p moved along the first estimate onto the 0.5 level (one Newton
 * step, at most SVDAG_SMOOTH_MAX_STEP voxels): hit points on neighbouring step faces lie up to a
 * voxel apart in depth, and evaluated there the normal would show the voxel grid as a texture;
 * on the level surface neighbouring pixels see neighbouring points. */
SVDAG_FN vec4 svdagSmoothNormalLift(SVDAG_STREAMS_PARAM SVDAG_NEIGHBOURS_PARAM uint midRefBits,
  uint leafRefBits, vec3 p, vec3 faceNormal, vec3 dir)
{
  if (faceNormal.x == 0.0f && faceNormal.y == 0.0f && faceNormal.z == 0.0f)
    return vec4(faceNormal, 0.0f);
  vec4 a = svdagOccupancyGradient(SVDAG_STREAMS_ARG SVDAG_NEIGHBOURS_ARG midRefBits, leafRefBits, p);
  if (a.x == 0.0f && a.y == 0.0f && a.z == 0.0f)
    return vec4(faceNormal, 0.0f);
  vec3 n = normalize(vec3(a));
  float below = a.w;
  // Only where the level surface is near: structures thinner than the kernel (a plate, a lone
  // voxel) never reach the 0.5 level, and there the step would jump across them.
  if (below >= -SVDAG_SMOOTH_MAX_STEP && below <= SVDAG_SMOOTH_MAX_STEP)
  {
    vec4 b = svdagOccupancyGradient(SVDAG_STREAMS_ARG SVDAG_NEIGHBOURS_ARG midRefBits,
      leafRefBits, p + below * n);
    vec3 nb = vec3(b);
    if (dot(nb, n) > 0.5f * length(nb)) // a consistent estimate (zero where it vanished)
      n = normalize(nb);
  }
  float lift = min(max(below, 0.0f) + 0.5f, SVDAG_SMOOTH_MAX_LIFT);
  // Towards the viewer: the face normal faces it (an entry face), so adding k * face raises
  // dot(n, -dir) to SVDAG_SMOOTH_MIN_COS.
  vec3 wo = -normalize(dir);
  float facing = dot(n, wo);
  float faceFacing = dot(faceNormal, wo);
  if (facing < SVDAG_SMOOTH_MIN_COS && faceFacing > 0.0f)
  {
    n = n + ((SVDAG_SMOOTH_MIN_COS - facing) / faceFacing) * faceNormal;
    n = normalize(n);
  }
  return vec4(n, lift);
}

/* The unit shading normal alone (svdagSmoothNormalLift's xyz). */
SVDAG_FN vec3 svdagSmoothNormal(SVDAG_STREAMS_PARAM SVDAG_NEIGHBOURS_PARAM uint midRefBits,
  uint leafRefBits, vec3 p, vec3 faceNormal, vec3 dir)
{
  return vec3(svdagSmoothNormalLift(SVDAG_STREAMS_ARG SVDAG_NEIGHBOURS_ARG midRefBits,
    leafRefBits, p, faceNormal, dir));
}

#ifdef __cplusplus
} // namespace traversal
} // namespace svdag
#endif

#endif
