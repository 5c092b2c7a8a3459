// A fixture for layering/Layering.CatchesUpwardIncludes: the rasteriser must not include the
// trainer, so the layering check has to name this file and this include.
#include "method/raster/blend.h"
#include "method/train/trainer.h"
