// The path tracer's feature switches (specialization constants, GpuLayout.h's SVDAG_CONSTANT_*
// ids; Pipeline.h's ShaderFeatures): a scene that does not use a feature does not pay for it
// (the host computes them from the scene and rebuilds the pipeline when they change). Included
// before the traversal, which the preview simplifies too.
#ifndef SVDAG_RENDER_FEATURES_GLSL
#define SVDAG_RENDER_FEATURES_GLSL

layout(constant_id = SVDAG_CONSTANT_NEE) const bool featureNee = true;
layout(constant_id = SVDAG_CONSTANT_ENV_MAP) const bool featureEnvMap = false;
layout(constant_id = SVDAG_CONSTANT_SUN) const bool featureSun = false;
layout(constant_id = SVDAG_CONSTANT_EMISSION) const bool featureEmission = false;
layout(constant_id = SVDAG_CONSTANT_TRANSMISSION) const bool featureTransmission = false;
layout(constant_id = SVDAG_CONSTANT_PREVIEW) const bool featurePreview = false;
layout(constant_id = SVDAG_CONSTANT_SMOOTH_SHADING) const bool featureSmoothShading = false;
layout(constant_id = SVDAG_CONSTANT_CLIPPING) const bool featureClipping = false;
#define SVDAG_FEATURE_NEE featureNee
#define SVDAG_FEATURE_ENV_MAP featureEnvMap
#define SVDAG_FEATURE_SUN featureSun
#define SVDAG_FEATURE_EMISSION featureEmission
#define SVDAG_FEATURE_TRANSMISSION featureTransmission
#define SVDAG_FEATURE_PREVIEW featurePreview
#define SVDAG_FEATURE_SMOOTH_SHADING featureSmoothShading
#define SVDAG_FEATURE_CLIPPING featureClipping

#endif
