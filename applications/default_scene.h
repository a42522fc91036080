#ifndef SPINESIM_APPLICATIONS_DEFAULT_SCENE_H
#define SPINESIM_APPLICATIONS_DEFAULT_SCENE_H

// The scene `spinesim run` uses without a scene file: applications/scenes/default.prm,
// embedded into the binary at build time.

namespace spinesim {
extern const char* const default_scene_text;
}

#endif
