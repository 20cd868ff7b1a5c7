/* Every public header of libbkfront, for programs that use the library (in C
 * or C++).  Library code includes the headers it needs, never this one: the
 * layers (CONTRIBUTING.md) would not hold. */
#ifndef BKFRONT_BKFRONT_H
#define BKFRONT_BKFRONT_H

#include "bkfront/status.h"
#include "bkfront/version.h"
#include "bkfront/fft.h"
#include "bkfront/model.h"
#include "bkfront/io.h"
#include "bkfront/h5.h"
#include "bkfront/asymptotics.h"
#include "bkfront/continuation.h"
#include "bkfront/cycle.h"
#include "bkfront/speeds.h"
#include "bkfront/chainwave.h"
#include "bkfront/asymfit.h"
#include "bkfront/floquet.h"
#include "bkfront/hill.h"
#include "bkfront/trainspec.h"
#include "bkfront/pde.h"
#include "bkfront/comoving.h"
#include "bkfront/measure.h"
#include "bkfront/bench.h"
#include "bkfront/catalog.h"
#include "bkfront/check.h"
#include "bkfront/options.h"
#include "bkfront/approx.h"
#include "bkfront/period.h"
#include "bkfront/profile.h"
#include "bkfront/friction.h"
#include "bkfront/fronts.h"
#include "bkfront/stability.h"
#include "bkfront/stabmap.h"
#include "bkfront/oscillation.h"
#include "bkfront/init.h"
#include "bkfront/seed.h"
#include "bkfront/simulate.h"
#include "bkfront/sweep.h"
#include "bkfront/plot.h"
#include "bkfront/scene.h"

#endif
