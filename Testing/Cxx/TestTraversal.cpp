// CPU ray traversal (Traversal.h through RayCaster) against an independent brute force.
//
// The brute force never looks at the SVDAG: it takes the raw label array, makes the boxes a LOD
// must hit (solid voxels; non-empty 4^3 leaf cubes clipped to the block bounds; the tight bounds
// of each label in each 16^3 cell) and slab-tests every box in double precision.
//
// Contacts of zero length (a ray touching a box at a face, edge or corner) are legitimately
// ambiguous (Traversal.h), so the brute force keeps two answers: boxes entered with a positive
// length inside ("strict") and boxes merely reached ("closed"), both up to a tolerance. The caster
// must hit when some box is strictly hit, miss when none is reached, and its t must lie between
// the closed and the strict minimum; the label, voxel and normal it reports must belong to a box
// reached at that t.
#include "svdag/Builder.h"
#include "svdag/RayCaster.h"
#include "svdag/Traversal.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <cstdlib>
#include <random>
#include <sstream>
#include <string>
#include <thread>

namespace
{
using svdag::Lod;
using Vec3 = std::array<double, 3>;

struct Box
{
  Vec3 lo, hi; // index space, [lo, hi]
  uint32_t label;
};

struct LabelVolume
{
  std::string name;
  std::array<int32_t, 3> dims;
  std::vector<uint32_t> labels; // x fastest, 0 = background
  uint32_t at(int x, int y, int z) const
  {
    return labels[size_t(x) + size_t(dims[0]) * (size_t(y) + size_t(dims[1]) * size_t(z))];
  }
};

// The boxes a LOD must hit, computed from the raw labels only.
std::vector<Box> referenceBoxes(const LabelVolume& v, Lod lod)
{
  std::vector<Box> boxes;
  const auto& d = v.dims;
  if (lod == Lod::Voxel)
  {
    for (int z = 0; z < d[2]; ++z)
      for (int y = 0; y < d[1]; ++y)
        for (int x = 0; x < d[0]; ++x)
          if (v.at(x, y, z) != 0)
            boxes.push_back({ { double(x), double(y), double(z) },
              { x + 1.0, y + 1.0, z + 1.0 }, v.at(x, y, z) });
    return boxes;
  }
  // Per 16^3 cell and label: tight bounds, and the 4^3 leaf cubes holding the label.
  for (int cz = 0; cz < d[2]; cz += 16)
    for (int cy = 0; cy < d[1]; cy += 16)
      for (int cx = 0; cx < d[0]; cx += 16)
      {
        std::map<uint32_t, std::array<int, 6>> bounds; // label -> xmin, ymin, zmin, xmax, ...
        std::map<uint32_t, std::vector<bool>> leaves;  // label -> 64 leaf cubes of the cell
        for (int z = cz; z < std::min(cz + 16, d[2]); ++z)
          for (int y = cy; y < std::min(cy + 16, d[1]); ++y)
            for (int x = cx; x < std::min(cx + 16, d[0]); ++x)
            {
              const uint32_t l = v.at(x, y, z);
              if (l == 0)
                continue;
              auto it = bounds.find(l);
              if (it == bounds.end())
              {
                bounds[l] = { x, y, z, x, y, z };
                leaves[l].assign(64, false);
              }
              else
              {
                auto& b = it->second;
                b = { std::min(b[0], x), std::min(b[1], y), std::min(b[2], z),
                  std::max(b[3], x), std::max(b[4], y), std::max(b[5], z) };
              }
              leaves[l][size_t((x - cx) / 4 + 4 * ((y - cy) / 4) + 16 * ((z - cz) / 4))] = true;
            }
        for (const auto& [label, b] : bounds)
        {
          Box block{ { double(b[0]), double(b[1]), double(b[2]) },
            { b[3] + 1.0, b[4] + 1.0, b[5] + 1.0 }, label };
          if (lod == Lod::Block)
          {
            boxes.push_back(block);
            continue;
          }
          for (int i = 0; i < 64; ++i)
          {
            if (!leaves[label][size_t(i)])
              continue;
            const int corner[3] = { cx + 4 * (i % 4), cy + 4 * ((i / 4) % 4), cz + 4 * (i / 16) };
            Box leaf{ {}, {}, label };
            for (int a = 0; a < 3; ++a)
            {
              leaf.lo[a] = std::max(block.lo[a], double(corner[a]));
              leaf.hi[a] = std::min(block.hi[a], double(corner[a] + 4));
            }
            boxes.push_back(leaf);
          }
        }
      }
  return boxes;
}

double norm(const Vec3& d)
{
  return std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
}

// Parameter interval of the ray inside a box, clipped to [tmin, tmax]; false if none. Axes with a
// zero direction are half-open, like voxels: inside iff lo <= origin < hi.
bool slab(const svdag::Ray& r, const Box& b, double& enter, double& exit)
{
  enter = r.tmin;
  exit = r.tmax;
  const double len = norm(r.direction);
  for (int a = 0; a < 3; ++a)
  {
    const double o = r.origin[a], dir = r.direction[a];
    if (std::fabs(dir) / len < 1e-30)
    {
      if (o < b.lo[a] || o >= b.hi[a])
        return false;
      continue;
    }
    const double t0 = (b.lo[a] - o) / dir, t1 = (b.hi[a] - o) / dir;
    enter = std::max(enter, std::min(t0, t1));
    exit = std::min(exit, std::max(t0, t1));
  }
  return true;
}

struct Expected
{
  double strictMin = std::numeric_limits<double>::infinity();
  double closedMin = std::numeric_limits<double>::infinity();
};

// Tolerance in distance units around a distance dist (1e-4 relative + 1e-4 absolute).
double tolerance(double dist)
{
  return 1e-4 * (1 + std::fabs(dist));
}

// Checks one cast against the boxes; returns an empty string or what is wrong.
std::string check(const svdag::Ray& r, const svdag::RayHit& hit, const std::vector<Box>& boxes,
  const svdag::Volume& volume)
{
  const double len = norm(r.direction);
  Expected e;
  for (const Box& b : boxes)
  {
    double enter, exit;
    if (!slab(r, b, enter, exit))
      continue;
    const double contact = (exit - enter) * len;
    const double tol = tolerance(enter * len);
    if (contact > tol)
      e.strictMin = std::min(e.strictMin, enter);
    if (contact >= -tol)
      e.closedMin = std::min(e.closedMin, enter);
  }
  std::ostringstream why;
  const bool mustHit = std::isfinite(e.strictMin);
  const bool mayHit = std::isfinite(e.closedMin);
  if (mustHit && !hit.hit)
    return "missed; expected a hit at t = " + std::to_string(e.strictMin);
  if (!mayHit && hit.hit)
    return "hit at t = " + std::to_string(hit.t) + " where nothing is reached";
  if (!hit.hit)
    return "";
  const double dist = hit.t * len;
  const double tol = tolerance(dist);
  if (dist < e.closedMin * len - tol || (mustHit && dist > e.strictMin * len + tol))
  {
    why << "t = " << hit.t << " outside [" << e.closedMin << ", " << e.strictMin << "]";
    return why.str();
  }
  // The label and voxel reported belong to a box reached at the hit's t.
  if (hit.label >= volume.labels.size())
    return "label index out of range";
  const uint32_t label = uint32_t(volume.labels[hit.label].value);
  bool found = false;
  for (const Box& b : boxes)
  {
    if (b.label != label)
      continue;
    bool contains = true;
    for (int a = 0; a < 3; ++a)
      contains = contains && hit.voxel[a] >= b.lo[a] && hit.voxel[a] + 1 <= b.hi[a];
    double enter, exit;
    if (contains && slab(r, b, enter, exit) && (exit - enter) * len >= -tol &&
      std::fabs(enter * len - dist) <= tol)
      found = true;
  }
  if (!found)
  {
    why << "label " << label << " / voxel (" << hit.voxel[0] << "," << hit.voxel[1] << ","
        << hit.voxel[2] << ") not reached at t = " << hit.t;
    return why.str();
  }
  // Normal: the entry face of the hit box, or zero when the ray starts inside.
  int axes = 0;
  for (int a = 0; a < 3; ++a)
  {
    const int n = hit.normal[a];
    if (n == 0)
      continue;
    ++axes;
    if ((n != 1 && n != -1) || n * r.direction[a] >= 0)
      return "normal does not face the ray";
    const double face = n < 0 ? hit.voxel[a] : hit.voxel[a] + 1.0;
    if (std::fabs(r.origin[a] + hit.t * r.direction[a] - face) > 1e-3 * (1 + std::fabs(dist)))
      return "hit point is not on the normal's face";
  }
  if (axes > 1)
    return "normal has more than one axis";
  if (axes == 0 && (dist - r.tmin * len) > tol)
    return "zero normal although the ray did not start inside";
  return "";
}

// ---- volumes ----------------------------------------------------------------------------------

LabelVolume makeVolume(const std::string& name, std::array<int32_t, 3> dims,
  const std::function<uint32_t(int, int, int)>& label)
{
  LabelVolume v{ name, dims, {} };
  v.labels.resize(size_t(dims[0]) * size_t(dims[1]) * size_t(dims[2]));
  size_t i = 0;
  for (int z = 0; z < dims[2]; ++z)
    for (int y = 0; y < dims[1]; ++y)
      for (int x = 0; x < dims[0]; ++x)
        v.labels[i++] = label(x, y, z);
  return v;
}

std::vector<LabelVolume> volumes()
{
  std::mt19937 rng(2024);
  auto uniform = [&rng](double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); };
  std::vector<LabelVolume> out;
  out.push_back(makeVolume("sparse few labels 37x21x19", { 37, 21, 19 },
    [&](int, int, int) { return uniform(0, 1) < 0.04 ? uint32_t(1 + rng() % 3) : 0u; }));
  out.push_back(makeVolume("dense many labels 37x21x19", { 37, 21, 19 },
    [&](int, int, int) { return uint32_t(1 + rng() % 50); }));
  out.push_back(makeVolume("1x1x1", { 1, 1, 1 }, [](int, int, int) { return 7u; }));
  out.push_back(makeVolume("full 16x16x16", { 16, 16, 16 }, [](int, int, int) { return 3u; }));
  out.push_back(makeVolume("sparse 33x1x17", { 33, 1, 17 },
    [&](int, int, int) { return uniform(0, 1) < 0.3 ? uint32_t(1 + rng() % 4) : 0u; }));
  // Smooth shapes: full and empty octants and leaves, complemented subtrees, shared faces.
  out.push_back(makeVolume("nested spheres 40x35x30", { 40, 35, 30 }, [](int x, int y, int z) {
    const double r2 = (x - 18.5) * (x - 18.5) + (y - 16.2) * (y - 16.2) + (z - 14.7) * (z - 14.7);
    return r2 < 60 ? 1u : (r2 < 150 ? 2u : (r2 < 260 ? 3u : 0u));
  }));
  out.push_back(makeVolume("slabs and boxes 34x20x33", { 34, 20, 33 }, [](int x, int y, int z) {
    if (x >= 3 && x < 29 && y >= 2 && y < 18 && z >= 8 && z < 24)
      return 1u + uint32_t(((x / 8) + (z / 8)) % 3);
    return y == 0 ? 5u : 0u;
  }));
  // Small clusters far apart: most regions of 4^3 cells are empty, so the walk crosses them in
  // one step (GridTraversal.h), partly empty regions at the grid's clipped edges included.
  out.push_back(makeVolume("clusters 210x180x150", { 210, 180, 150 }, [](int x, int y, int z) {
    const int centers[5][3] = { { 20, 30, 25 }, { 150, 40, 120 }, { 100, 170, 60 },
      { 200, 100, 140 }, { 70, 90, 80 } };
    for (int c = 0; c < 5; ++c)
    {
      const int dx = x - centers[c][0], dy = y - centers[c][1], dz = z - centers[c][2];
      if (dx * dx + dy * dy + dz * dz < 400 + 60 * c)
        return uint32_t(1 + c % 3);
    }
    // A thin rod along the diagonal.
    return (std::abs(x - y) <= 1 && std::abs(y - (z + 15)) <= 1) ? 4u : 0u;
  }));
  // A long thin volume: rays from far away cross many cells (cell DDA, float re-anchoring).
  out.push_back(makeVolume("long 1500x6x5", { 1500, 6, 5 },
    [&](int x, int, int) { return (x % 97 == 13 || uniform(0, 1) < 0.03) ? 1u + uint32_t(x % 3) : 0u; }));
  return out;
}

// ---- rays -------------------------------------------------------------------------------------

std::vector<svdag::Ray> rays(const std::array<int32_t, 3>& dims, unsigned seed, int count)
{
  std::mt19937 rng(seed);
  auto uniform = [&rng](double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); };
  auto pick = [&rng](int n) { return int(rng() % unsigned(n)); };
  const Vec3 size{ double(dims[0]), double(dims[1]), double(dims[2]) };
  const double diag = norm(size);
  auto inside = [&](double margin) {
    return Vec3{ uniform(-margin, size[0] + margin), uniform(-margin, size[1] + margin),
      uniform(-margin, size[2] + margin) };
  };
  auto intPoint = [&](int margin) {
    return Vec3{ double(pick(dims[0] + 2 * margin + 1) - margin),
      double(pick(dims[1] + 2 * margin + 1) - margin), double(pick(dims[2] + 2 * margin + 1) - margin) };
  };
  std::vector<svdag::Ray> out;
  for (int i = 0; i < count; ++i)
  {
    svdag::Ray r;
    const int kind = i % 8;
    if (kind == 0) // from outside towards a random point inside
    {
      const Vec3 target = inside(0);
      Vec3 dir{ uniform(-1, 1), uniform(-1, 1), uniform(-1, 1) };
      const double n = norm(dir) + 1e-9;
      for (int a = 0; a < 3; ++a)
        r.origin[a] = target[a] - dir[a] / n * (diag + 5);
      for (int a = 0; a < 3; ++a)
        r.direction[a] = (target[a] - r.origin[a]) * uniform(0.05, 3); // not unit length
    }
    else if (kind == 1) // starting anywhere inside (often in a solid voxel), random direction
    {
      r.origin = inside(0);
      r.direction = { uniform(-1, 1), uniform(-1, 1), uniform(-1, 1) };
    }
    else if (kind == 2) // axis-aligned
    {
      r.origin = pick(2) ? inside(2) : intPoint(2);
      r.direction = { 0, 0, 0 };
      r.direction[size_t(pick(3))] = pick(2) ? 1 : -1;
    }
    else if (kind == 3) // one or two zero components
    {
      r.origin = pick(3) ? inside(3) : intPoint(3);
      r.direction = { uniform(-1, 1), uniform(-1, 1), uniform(-1, 1) };
      r.direction[size_t(pick(3))] = 0;
      if (pick(2))
        r.direction[size_t(pick(3))] = 0;
      if (r.direction == Vec3{ 0, 0, 0 })
        r.direction[size_t(pick(3))] = 1;
    }
    else if (kind == 4) // through voxel corners and edges: integer origins and directions
    {
      r.origin = intPoint(3);
      static const Vec3 dirs[] = { { 1, 1, 0 }, { 1, -1, 0 }, { 0, 1, 1 }, { 1, 0, -1 },
        { 1, 1, 1 }, { -1, 1, -1 }, { 2, 1, 0 }, { 1, 2, 3 }, { -1, -1, -1 }, { 0, 0, 1 } };
      r.direction = dirs[pick(10)];
      if (pick(2))
        for (double& c : r.direction)
          c = -c;
    }
    else if (kind == 5) // grazing: along a voxel face plane (an integer coordinate, zero direction)
    {
      r.origin = inside(1);
      const int a = pick(3);
      r.origin[size_t(a)] = double(pick(dims[a] + 1));
      r.direction = { uniform(-1, 1), uniform(-1, 1), uniform(-1, 1) };
      r.direction[size_t(a)] = 0;
    }
    else if (kind == 6) // a sub-interval [tmin, tmax] of a ray through the volume
    {
      r.origin = inside(4);
      r.direction = { uniform(-1, 1), uniform(-1, 1), uniform(-1, 1) };
      r.tmin = uniform(-2, diag / 2);
      r.tmax = r.tmin + uniform(0, diag / 2);
    }
    else // from far away (precision of the re-anchoring)
    {
      const Vec3 target = inside(0);
      Vec3 dir{ uniform(-1, 1), uniform(-1, 1), uniform(-1, 1) };
      const double n = norm(dir) + 1e-9;
      for (int a = 0; a < 3; ++a)
      {
        r.direction[a] = dir[a] / n;
        r.origin[a] = target[a] - r.direction[a] * 3000;
      }
    }
    out.push_back(r);
  }
  return out;
}

std::string describe(const svdag::Ray& r)
{
  std::ostringstream s;
  s.precision(17);
  s << "origin (" << r.origin[0] << ", " << r.origin[1] << ", " << r.origin[2] << ") direction ("
    << r.direction[0] << ", " << r.direction[1] << ", " << r.direction[2] << ") t in [" << r.tmin
    << ", " << r.tmax << "]";
  return s.str();
}

const char* lodName(Lod lod)
{
  return lod == Lod::Block ? "block" : (lod == Lod::Leaf ? "leaf" : "voxel");
}

svdag::Volume compress(const LabelVolume& v)
{
  svdag::Geometry g;
  g.dims = v.dims;
  return svdag::Builder::build(g, svdag::ScalarType::UInt32, v.labels.data());
}


// ---- entry-only rays (Traversal.h, "Entry only") ------------------------------------------------

// The boxes an entry-only ray may hit: per block, i.e. per (16^3 cell, label), the boxes of that
// block minus the solid run the ray starts in (the boxes it is inside at tmin and those chained to
// them along the ray, each starting within `gap` of where the run so far ends). Boxes of other
// blocks, even of the same label in the next cell, stay: the ray enters them.
std::vector<Box> entryBoxes(const svdag::Ray& r, const std::vector<Box>& boxes, double gap)
{
  const double len = norm(r.direction);
  struct Span
  {
    double enter, exit;
    size_t box;
  };
  std::map<std::array<int64_t, 4>, std::vector<Span>> blocks;
  std::vector<bool> keep(boxes.size(), true);
  for (size_t i = 0; i < boxes.size(); ++i)
  {
    const Box& b = boxes[i];
    std::array<int64_t, 4> key{ int64_t(std::floor(b.lo[0] / 16)), int64_t(std::floor(b.lo[1] / 16)),
      int64_t(std::floor(b.lo[2] / 16)), int64_t(b.label) };
    double enter, exit;
    if (slab(r, b, enter, exit) && exit > enter)
      blocks[key].push_back({ enter, exit, i });
  }
  for (auto& [key, spans] : blocks)
  {
    std::sort(spans.begin(), spans.end(), [](const Span& a, const Span& b) { return a.enter < b.enter; });
    double runEnd = r.tmin; // the run starts at tmin, if a box holds the start point
    for (const Span& s : spans)
    {
      if ((s.enter - runEnd) * len > gap)
        break;
      keep[s.box] = false;
      runEnd = std::max(runEnd, s.exit);
    }
  }
  std::vector<Box> out;
  for (size_t i = 0; i < boxes.size(); ++i)
    if (keep[i])
      out.push_back(boxes[i]);
  return out;
}

// Rays starting inside solid voxels (at tmin, sometimes tmin != 0), in random directions.
std::vector<svdag::Ray> raysFromSolids(const LabelVolume& v, unsigned seed, int count)
{
  std::mt19937 rng(seed);
  auto uniform = [&rng](double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); };
  std::vector<std::array<int, 3>> solids;
  for (int z = 0; z < v.dims[2]; ++z)
    for (int y = 0; y < v.dims[1]; ++y)
      for (int x = 0; x < v.dims[0]; ++x)
        if (v.at(x, y, z) != 0)
          solids.push_back({ x, y, z });
  std::vector<svdag::Ray> out;
  for (int i = 0; i < count && !solids.empty(); ++i)
  {
    const auto& voxel = solids[rng() % solids.size()];
    svdag::Ray r;
    Vec3 start;
    for (int a = 0; a < 3; ++a)
    {
      start[a] = voxel[a] + uniform(0.02, 0.98);
      r.direction[a] = uniform(-1, 1);
    }
    if (i % 5 == 4) // one zero component
      r.direction[size_t(i % 3)] = 0;
    if (r.direction == Vec3{ 0, 0, 0 })
      r.direction[0] = 1;
    r.tmin = i % 3 == 0 ? uniform(-5, 5) : 0.0;
    for (int a = 0; a < 3; ++a)
      r.origin[a] = start[a] - r.tmin * r.direction[a];
    r.entryOnly = true;
    out.push_back(r);
  }
  return out;
}

} // namespace

TEST(Traversal, MatchesBruteForceAtEveryLod)
{
  unsigned seed = 1;
  for (const LabelVolume& v : volumes())
  {
    const svdag::Volume volume = compress(v);
    const svdag::RayCaster caster(volume);
    const int count = v.labels.size() > 5000 ? 1500 : 3000;
    const std::vector<svdag::Ray> testRays = rays(v.dims, seed++, count);
    for (Lod lod : { Lod::Block, Lod::Leaf, Lod::Voxel })
    {
      const std::vector<Box> boxes = referenceBoxes(v, lod);
      int hits = 0, failures = 0;
      for (const svdag::Ray& r : testRays)
      {
        const svdag::RayHit hit = caster.cast(r, lod);
        hits += hit.hit ? 1 : 0;
        const std::string why = check(r, hit, boxes, volume);
        if (!why.empty() && ++failures <= 5)
          ADD_FAILURE() << v.name << ", LOD " << lodName(lod) << ": " << why << "\n  ray "
                        << describe(r);
      }
      EXPECT_EQ(failures, 0) << v.name << ", LOD " << lodName(lod);
      // The ray sets must exercise both outcomes.
      EXPECT_GT(hits, count / 20) << v.name << ", LOD " << lodName(lod);
      EXPECT_LT(hits, count) << v.name << ", LOD " << lodName(lod);
    }
  }
}

TEST(Traversal, EntryOnlySkipsTheStartingSolidRun)
{
  // Against the brute force: the first solid box entered from outside its block's solid, the run
  // holding the start point ignored. Runs joined by a gap of zero length are ambiguous (a ray
  // grazing the edge between two diagonal voxels), so both readings (gap 1e-9 and 1e-4) are
  // accepted; a cast must satisfy one of them completely.
  unsigned seed = 300;
  for (const LabelVolume& v : volumes())
  {
    const svdag::Volume volume = compress(v);
    const svdag::RayCaster caster(volume);
    std::vector<svdag::Ray> testRays = raysFromSolids(v, seed++, 1500);
    // Also entry-only rays from anywhere (starting in an empty voxel changes nothing), from the
    // non-degenerate kinds of rays(): through an edge or corner shared by two solid boxes a run
    // may or may not continue (a zero-length contact), which neither reading decides.
    const std::vector<svdag::Ray> general = rays(v.dims, seed++, 800);
    for (size_t i = 0; i < general.size(); ++i)
    {
      const size_t kind = i % 8;
      if (kind != 0 && kind != 1 && kind != 6 && kind != 7)
        continue;
      svdag::Ray r = general[i];
      r.entryOnly = true;
      testRays.push_back(r);
    }
    for (Lod lod : { Lod::Block, Lod::Leaf, Lod::Voxel })
    {
      const std::vector<Box> boxes = referenceBoxes(v, lod);
      int hits = 0, failures = 0, differs = 0;
      for (const svdag::Ray& r : testRays)
      {
        const svdag::RayHit hit = caster.cast(r, lod);
        hits += hit.hit ? 1 : 0;
        std::string why = check(r, hit, entryBoxes(r, boxes, 1e-9), volume);
        if (!why.empty() && check(r, hit, entryBoxes(r, boxes, 1e-4), volume).empty())
          why.clear();
        if (why.empty() && hit.hit && hit.normal == std::array<int32_t, 3>{ { 0, 0, 0 } })
          why = "entry-only hit without an entry face";
        if (!why.empty() && ++failures <= 5)
          ADD_FAILURE() << v.name << ", LOD " << lodName(lod) << ": " << why << "\n  ray "
                        << describe(r);
        // Somewhere the plain query must answer differently (it hits at the start point).
        svdag::Ray plain = r;
        plain.entryOnly = false;
        const svdag::RayHit first = caster.cast(plain, lod);
        differs += (first.hit != hit.hit || first.t != hit.t) ? 1 : 0;
      }
      EXPECT_EQ(failures, 0) << v.name << ", LOD " << lodName(lod);
      EXPECT_GT(differs, 0) << v.name << ", LOD " << lodName(lod);
      if (v.name.rfind("dense", 0) == 0 || v.name.rfind("sparse", 0) == 0)
        EXPECT_GT(hits, 0) << v.name << ", LOD " << lodName(lod);
    }
  }
}

TEST(Traversal, EntryOnlyExamples)
{
  // Two labels in a row along x inside one cell: 3 in x < 6, 4 in 6 <= x < 9, empty beyond, and
  // label 3 again at 12 <= x < 14.
  const LabelVolume v = makeVolume("row", { 16, 4, 4 }, [](int x, int, int) {
    return x < 6 ? 3u : (x < 9 ? 4u : (x >= 12 && x < 14 ? 3u : 0u));
  });
  const svdag::Volume volume = compress(v);
  const svdag::RayCaster caster(volume);
  svdag::Ray r;
  r.origin = { 2.5, 1.5, 1.5 };
  r.direction = { 1, 0, 0 };
  r.entryOnly = true;
  // From inside label 3: label 4 is entered at x = 6 (a different block: an entry).
  svdag::RayHit hit = caster.cast(r, Lod::Voxel);
  ASSERT_TRUE(hit.hit);
  EXPECT_NEAR(hit.t, 3.5, 1e-5);
  EXPECT_EQ(volume.labels[hit.label].value, 4u);
  EXPECT_EQ(hit.normal, (std::array<int32_t, 3>{ { -1, 0, 0 } }));
  // From inside label 4: label 3 again at x = 12, after the gap.
  r.origin[0] = 7.5;
  hit = caster.cast(r, Lod::Voxel);
  ASSERT_TRUE(hit.hit);
  EXPECT_NEAR(hit.t, 4.5, 1e-5);
  EXPECT_EQ(volume.labels[hit.label].value, 3u);
  EXPECT_EQ(hit.voxel, (std::array<int32_t, 3>{ { 12, 1, 1 } }));
  // Backwards from inside label 4: label 3 touches it at x = 6, entered there.
  r.direction = { -1, 0, 0 };
  hit = caster.cast(r, Lod::Voxel);
  ASSERT_TRUE(hit.hit);
  EXPECT_NEAR(hit.t, 1.5, 1e-5);
  EXPECT_EQ(hit.normal, (std::array<int32_t, 3>{ { 1, 0, 0 } }));
  EXPECT_EQ(volume.labels[hit.label].value, 3u);
  // Inside label 3's last run, going +x: nothing is entered any more.
  r.origin[0] = 12.5;
  r.direction = { 1, 0, 0 };
  EXPECT_FALSE(caster.cast(r, Lod::Voxel).hit);
  // Block LOD: label 3's block box spans x 0..13, so from x = 2.5 only label 4's box is entered,
  // and from inside both boxes (x = 7.5) nothing is.
  r.origin[0] = 2.5;
  hit = caster.cast(r, Lod::Block);
  ASSERT_TRUE(hit.hit);
  EXPECT_EQ(volume.labels[hit.label].value, 4u);
  EXPECT_NEAR(hit.t, 3.5, 1e-5);
  r.origin[0] = 7.5;
  EXPECT_FALSE(caster.cast(r, Lod::Block).hit);
  // The plain query hits at the start point with no entry face.
  r.entryOnly = false;
  hit = caster.cast(r, Lod::Voxel);
  ASSERT_TRUE(hit.hit);
  EXPECT_EQ(hit.t, 0.0);
  EXPECT_EQ(hit.normal, (std::array<int32_t, 3>{ { 0, 0, 0 } }));
}

TEST(Traversal, CoarserLodsNeverHitLater)
{
  // Each LOD's boxes contain the next finer LOD's, so the hit can only move closer.
  const LabelVolume v = volumes()[5];
  const svdag::Volume volume = compress(v);
  const svdag::RayCaster caster(volume);
  for (const svdag::Ray& r : rays(v.dims, 99, 2000))
  {
    const svdag::RayHit block = caster.cast(r, Lod::Block);
    const svdag::RayHit leaf = caster.cast(r, Lod::Leaf);
    const svdag::RayHit voxel = caster.cast(r, Lod::Voxel);
    if (voxel.hit)
    {
      ASSERT_TRUE(leaf.hit) << describe(r);
      EXPECT_LE(leaf.t, voxel.t + 1e-4 * (1 + std::fabs(voxel.t))) << describe(r);
    }
    if (leaf.hit)
    {
      ASSERT_TRUE(block.hit) << describe(r);
      EXPECT_LE(block.t, leaf.t + 1e-4 * (1 + std::fabs(leaf.t))) << describe(r);
    }
  }
}

TEST(Traversal, StartingInsideASolidVoxel)
{
  const LabelVolume v = makeVolume("full", { 20, 20, 20 }, [](int, int, int) { return 4u; });
  const svdag::Volume volume = compress(v);
  const svdag::RayCaster caster(volume);
  svdag::Ray r;
  r.origin = { 5.25, 7.5, 9.75 };
  r.direction = { 0.3, -1, 0.2 };
  r.tmin = 0.25; // start point (5.325, 7.25, 9.8)
  for (Lod lod : { Lod::Block, Lod::Leaf, Lod::Voxel })
  {
    const svdag::RayHit hit = caster.cast(r, lod);
    ASSERT_TRUE(hit.hit);
    EXPECT_DOUBLE_EQ(hit.t, 0.25);
    EXPECT_EQ(hit.normal, (std::array<int32_t, 3>{ { 0, 0, 0 } }));
    EXPECT_EQ(volume.labels[hit.label].value, 4u);
  }
  // The voxel reported is the one holding the start point.
  EXPECT_EQ(caster.cast(r, Lod::Voxel).voxel, (std::array<int32_t, 3>{ { 5, 7, 9 } }));
}

TEST(Traversal, EntryFaceAndVoxel)
{
  // One solid voxel at (20, 5, 3) in an otherwise empty volume: entered from -x.
  const LabelVolume v = makeVolume(
    "one voxel", { 40, 9, 7 }, [](int x, int y, int z) { return x == 20 && y == 5 && z == 3 ? 9u : 0u; });
  const svdag::Volume volume = compress(v);
  const svdag::RayCaster caster(volume);
  svdag::Ray r;
  r.origin = { -10, 5.5, 3.5 };
  r.direction = { 2, 0, 0 }; // t counts in units of |direction|
  const svdag::RayHit hit = caster.cast(r, Lod::Voxel);
  ASSERT_TRUE(hit.hit);
  EXPECT_NEAR(hit.t, 15.0, 1e-5);
  EXPECT_EQ(hit.voxel, (std::array<int32_t, 3>{ { 20, 5, 3 } }));
  EXPECT_EQ(hit.normal, (std::array<int32_t, 3>{ { -1, 0, 0 } }));
  EXPECT_EQ(volume.labels[hit.label].value, 9u);
  // The same ray cut short of the voxel misses.
  r.tmax = 14.9;
  EXPECT_FALSE(caster.cast(r, Lod::Voxel).hit);
  // Along the voxel's top face plane y = 6 (half-open: belongs to row 6, which is empty).
  r = svdag::Ray();
  r.origin = { -10, 6, 3.5 };
  r.direction = { 1, 0, 0 };
  EXPECT_FALSE(caster.cast(r, Lod::Voxel).hit);
  r.origin[1] = 5; // bottom face plane y = 5 belongs to row 5: the ray grazes the voxel
  EXPECT_TRUE(caster.cast(r, Lod::Voxel).hit);
}

TEST(Traversal, EmptyVolumeAndInvalidRays)
{
  const LabelVolume empty = makeVolume("empty", { 17, 5, 3 }, [](int, int, int) { return 0u; });
  const svdag::Volume volume = compress(empty);
  const svdag::RayCaster caster(volume);
  svdag::Ray r;
  r.origin = { -1, 2.5, 1.5 };
  r.direction = { 1, 0, 0 };
  EXPECT_FALSE(caster.cast(r, Lod::Voxel).hit);
  r.direction = { 0, 0, 0 };
  EXPECT_THROW(caster.cast(r, Lod::Voxel), std::invalid_argument);
  r.direction = { 1, std::nan(""), 0 };
  EXPECT_THROW(caster.cast(r, Lod::Voxel), std::invalid_argument);
  r.direction = { 1, 0, 0 };
  r.origin[2] = std::numeric_limits<double>::infinity();
  EXPECT_THROW(caster.cast(r, Lod::Voxel), std::invalid_argument);
  r.origin[2] = 1.5;
  r.tmax = std::nan("");
  EXPECT_THROW(caster.cast(r, Lod::Voxel), std::invalid_argument);
  r.tmax = std::numeric_limits<double>::infinity(); // infinite bounds are fine
  EXPECT_NO_THROW(caster.cast(r, Lod::Voxel));
  EXPECT_THROW(caster.cast(r, Lod(7)), std::invalid_argument);
}

TEST(Traversal, CastManyMatchesCastOnThreads)
{
  const LabelVolume v = volumes()[1];
  const svdag::Volume volume = compress(v);
  const svdag::RayCaster caster(volume);
  const std::vector<svdag::Ray> testRays = rays(v.dims, 7, 1000);
  const svdag::ParallelFor threaded = [](uint64_t begin, uint64_t end, uint64_t grain,
                                        const svdag::RangeFunction& f) {
    std::vector<std::thread> pool;
    for (uint64_t b = begin; b < end; b += grain)
      pool.emplace_back([&f, b, end, grain] { f(b, std::min(end, b + grain)); });
    for (auto& t : pool)
      t.join();
  };
  std::vector<svdag::RayHit> hits;
  caster.castMany(testRays, Lod::Voxel, hits, threaded);
  ASSERT_EQ(hits.size(), testRays.size());
  for (size_t i = 0; i < testRays.size(); ++i)
  {
    const svdag::RayHit one = caster.cast(testRays[i], Lod::Voxel);
    ASSERT_EQ(hits[i].hit, one.hit);
    EXPECT_EQ(hits[i].t, one.t);
    EXPECT_EQ(hits[i].block, one.block);
    EXPECT_EQ(hits[i].voxel, one.voxel);
  }
  std::vector<svdag::Ray> bad = testRays;
  bad[500].direction = { 0, 0, 0 };
  EXPECT_THROW(caster.castMany(bad, Lod::Voxel, hits, threaded), std::invalid_argument);
}

TEST(Traversal, BlockFunctionDirectly)
{
  // The shared C++/GLSL function on one full block, without the caster around it.
  const LabelVolume v = makeVolume("full cell", { 16, 16, 16 }, [](int, int, int) { return 1u; });
  const svdag::Volume volume = compress(v);
  ASSERT_EQ(volume.blockCount, 1u);
  const svdag::Block b = volume.block(0);
  const svdag::traversal::Streams streams{ volume.roots.data(), volume.mids.data(),
    volume.leaves.data() };
  auto cast = [&](glm::vec3 origin, glm::vec3 dir, float tmin, float tmax) {
    return svdag::traversal::svdagIntersectBlock(streams, glm::uvec3(b.lo[0], b.lo[1], b.lo[2]),
      glm::uvec3(b.hi[0], b.hi[1], b.hi[2]), b.root, volume.widths.midRefBits,
      volume.widths.leafRefBits, origin, dir, tmin, tmax, svdag::traversal::SVDAG_LOD_VOXEL,
      false);
  };
  svdag::traversal::SvdagBlockHit h = cast({ 8.5f, 20.f, 3.5f }, { 0.f, -1.f, 0.f }, 0.f, 100.f);
  ASSERT_TRUE(h.hit);
  EXPECT_FLOAT_EQ(h.t, 4.f);
  EXPECT_EQ(h.normal, glm::ivec3(0, 1, 0));
  EXPECT_EQ(h.voxel, glm::ivec3(8, 15, 3));
  // Empty or NaN intervals and a zero direction never hit.
  EXPECT_FALSE(cast({ 8.5f, 8.5f, 8.5f }, { 1.f, 0.f, 0.f }, 2.f, 1.f).hit);
  EXPECT_FALSE(cast({ 8.5f, 8.5f, 8.5f }, { 1.f, 0.f, 0.f }, std::nanf(""), 1.f).hit);
  EXPECT_FALSE(cast({ 8.5f, 8.5f, 8.5f }, { 0.f, 0.f, 0.f }, 0.f, 1.f).hit);
  // Denormal components count as zero: no inf or NaN, the ray runs along the axis.
  h = cast({ -3.f, 8.5f, 8.5f }, { 1.f, 1e-40f, -1e-41f }, 0.f, 100.f);
  ASSERT_TRUE(h.hit);
  EXPECT_FLOAT_EQ(h.t, 3.f);
  EXPECT_EQ(h.voxel, glm::ivec3(0, 8, 8));
}
