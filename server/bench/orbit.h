/* orbit.h -- the built-in smooth light path of `iird bench` when no --anim is given: the scene's
 * first spot circles about the vertical through its position while its aim point circles the other
 * way, one full turn over the run. */
#ifndef IIRD_ORBIT_H
#define IIRD_ORBIT_H

#include "iir/rt.h"
#include "iir/scene.h"

/* The light for frame f of `frames`. `base` is the scene's spot; the radii are 15% of the scene
 * diagonal. */
iir_light iird_orbit_light(const iir_scene *scene, const iir_rt *rt, const iir_light *base, int f,
                           int frames);

#endif
