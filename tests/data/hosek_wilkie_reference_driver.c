/* One-off: evaluate the authors' reference Hosek-Wilkie 1.4a C code on cases read from stdin.
   Input lines: kind T albedo sun_elev theta gamma wl_or_channel
   kind 0 = arhosekskymodel_radiance (spectral sky), 1 = arhosek_tristim XYZ, 2 = tristim RGB,
   3 = arhosekskymodel_solar_radiance (sky + sun), 4 = solar_radiance_internal2 (sun alone; elevation = pi/2 - theta). */
#include <stdio.h>
#include <math.h>
#include "ArHosekSkyModel.h"
double arhosekskymodel_solar_radiance_internal2(ArHosekSkyModelState*, double, double, double);
int main(void) {
  int kind; double T, a, e, th, g, w;
  while (scanf("%d %lf %lf %lf %lf %lf %lf", &kind, &T, &a, &e, &th, &g, &w) == 7) {
    double r = 0;
    ArHosekSkyModelState *s;
    if (kind == 0 || kind == 3 || kind == 4) s = arhosekskymodelstate_alloc_init(e, T, a);
    else if (kind == 1) s = arhosek_xyz_skymodelstate_alloc_init(T, a, e);
    else s = arhosek_rgb_skymodelstate_alloc_init(T, a, e);
    if (kind == 0) r = arhosekskymodel_radiance(s, th, g, w);
    else if (kind == 1 || kind == 2) r = arhosek_tristim_skymodel_radiance(s, th, g, (int)w);
    else if (kind == 3) r = arhosekskymodel_solar_radiance(s, th, g, w);
    else r = arhosekskymodel_solar_radiance_internal2(s, w, M_PI/2 - th, g);
    printf("%.17g\n", r);
    arhosekskymodelstate_free(s);
  }
  return 0;
}
