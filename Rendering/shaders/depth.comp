#version 460
// The depth pass (DepthLayout.h): window depth to ray limits before a trace, traced hits to
// window depth after it, for a scene depth that OpenGL wrote into exported memory. Every value is
// computed as the volume mapper computes it on the host (rayLimits and compositedDepth in
// vtkSegmentationSVDAGVolumeMapper.cxx, and the advance of the rays in Renderer::render), in the
// same order of double operations, and `precise` keeps the compiler from fusing or reordering
// them, so that both paths give the same bits. std::max(a, b) and std::min(a, b) are written out
// as the ternaries they are ((a < b) ? b : a and (b < a) ? b : a): their NaN cases differ from
// GLSL's max and min.
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference_uvec2 : require

#include "svdag_render/DepthLayout.h"

layout(local_size_x = SVDAG_DEPTH_GROUP_SIZE, local_size_y = SVDAG_DEPTH_GROUP_SIZE) in;

layout(push_constant) uniform DepthPush
{
  uvec2 params; // the address of the DepthParams
} push;

layout(buffer_reference, std430, buffer_reference_align = 4) readonly buffer DepthFloats
{
  float v[];
};
layout(buffer_reference, std430, buffer_reference_align = 4) readonly buffer DepthUints
{
  uint v[];
};
layout(buffer_reference, std430, buffer_reference_align = 4) writeonly buffer DepthOutput
{
  float v[];
};

layout(buffer_reference, std430, buffer_reference_align = 32) readonly buffer DepthParamsBuffer
{
  DepthParams params;
};

// The parameters, loaded once per invocation (a member of the buffer would be a load per use).
DepthParams p;

// The mapper's imageCoordinate: pixel center i of n in [-1, 1].
double imageCoordinate(uint i, uint n)
{
  precise double c = 2.0 * (double(i) + 0.5) / double(n) - 1.0;
  return c;
}

// The mapper's rayAt: the ray through image point (u, v), unit direction.
void rayAt(double u, double v, out dvec3 origin, out dvec3 direction)
{
  precise dvec3 o, span, d;
  for (int a = 0; a < 3; ++a)
  {
    o[a] = p.origin[a] + u * p.originU[a] + v * p.originV[a];
    span[a] = p.direction[a] + u * p.directionU[a] + v * p.directionV[a];
  }
  precise double spanLength = sqrt(span[0] * span[0] + span[1] * span[1] + span[2] * span[2]);
  for (int a = 0; a < 3; ++a)
    d[a] = span[a] / spanLength;
  origin = o;
  direction = d;
}

// Renderer::render's advance at pixel (x, y): how much closer the traced rays started.
double advanced(double u, double v)
{
  precise double advance = p.scalars.x;
  if (!(advance > 0.0))
    return 0.0;
  precise dvec3 span;
  for (int a = 0; a < 3; ++a)
    span[a] = p.tracedDirection[a] + u * p.tracedDirectionU[a] + v * p.tracedDirectionV[a];
  precise double result = advance * sqrt(span[0] * span[0] + span[1] * span[1] + span[2] * span[2]);
  return result;
}

// Per traced pixel: the ray distance to the scene's surface, past it by the slack, less the
// advance (FLT_MAX where nothing was drawn).
void rayLimit(uvec2 pixel)
{
  uint width = p.sizes.z, height = p.sizes.w;
  uint vpWidth = p.sizes.x, vpHeight = p.sizes.y;
  double u = imageCoordinate(pixel.x, width);
  double v = imageCoordinate(pixel.y, height);
  precise double fyReal = (double(pixel.y) + 0.5) * double(vpHeight) / double(height);
  precise double fxReal = (double(pixel.x) + 0.5) * double(vpWidth) / double(width);
  int fy = min(int(fyReal), int(vpHeight) - 1);
  int fx = min(int(fxReal), int(vpWidth) - 1);
  float d = DepthFloats(p.depth.xy).v[uint(fx) + vpWidth * uint(fy)];
  float limit = SVDAG_RAY_NOT_LIMITED;
  if (d < 1.0)
  {
    precise dvec4 clip = dvec4(u, v, 2.0 * double(d) - 1.0, 1.0);
    precise dvec4 q = dvec4(0.0);
    for (int row = 0; row < 4; ++row)
    {
      for (int c = 0; c < 4; ++c)
        q[row] += p.matrix[row][c] * clip[c];
    }
    dvec3 origin, direction;
    rayAt(u, v, origin, direction);
    precise double t = 0.0;
    for (int a = 0; a < 3; ++a)
      t += (q[a] / q[3] - origin[a]) * direction[a];
    precise double slack = (t < 0.0 ? 0.0 : t) * p.scalars.y;
    limit = float(slack);
  }
  precise double relative = double(limit) - advanced(u, v);
  DepthOutput(p.depth.zw).v[pixel.x + width * pixel.y] = float(0.0 < relative ? relative : 0.0);
}

// Per viewport pixel: the nearer of the scene's window depth and the traced hit's covering it.
void compositeDepth(uvec2 pixel)
{
  uint width = p.sizes.z, height = p.sizes.w;
  uint vpWidth = p.sizes.x, vpHeight = p.sizes.y;
  uint x = min(pixel.x * width / vpWidth, width - 1u);
  uint y = min(pixel.y * height / vpHeight, height - 1u);
  uint i = x + width * y;
  float traced = 1.0;
  if (DepthUints(p.traced.xy).v[i] != 0u)
  {
    double u = imageCoordinate(x, width);
    double v = imageCoordinate(y, height);
    // The traced depth as Renderer::image() holds it: relative to the rays as given.
    float t = DepthFloats(p.traced.zw).v[i];
    if (p.scalars.x > 0.0)
    {
      precise double given = double(t) + advanced(u, v);
      t = float(given);
    }
    dvec3 origin, direction;
    rayAt(u, v, origin, direction);
    precise dvec4 q = dvec4(origin + double(t) * direction, 1.0);
    precise double z = 0.0, w = 0.0;
    for (int c = 0; c < 4; ++c)
    {
      z += p.matrix[2][c] * q[c];
      w += p.matrix[3][c] * q[c];
    }
    precise double window = 0.5 * z / w + 0.5;
    window = window < 0.0 ? 0.0 : window;
    window = 1.0 < window ? 1.0 : window;
    traced = float(window);
  }
  float scene = DepthFloats(p.depth.xy).v[pixel.x + vpWidth * pixel.y];
  DepthOutput(p.depth.zw).v[pixel.x + vpWidth * pixel.y] = traced < scene ? traced : scene;
}

void main()
{
  p = DepthParamsBuffer(push.params).params;
  uvec2 pixel = gl_GlobalInvocationID.xy;
  if (p.pass.x == SVDAG_DEPTH_PASS_LIMITS)
  {
    if (pixel.x < p.sizes.z && pixel.y < p.sizes.w)
      rayLimit(pixel);
  }
  else if (pixel.x < p.sizes.x && pixel.y < p.sizes.y)
  {
    compositeDepth(pixel);
  }
}
