#pragma once
// Why --compare-pcl cannot run in this build, for its one-line error. PRIMLABEL_WITH_PCL is ON
// by default, so the usual cause is PCL not found at configure time (no libpcl-dev), not the
// option; the build passes PRIMLABEL_WITH_PCL_OPTION (0 or 1) to tell them apart.

#include <string>

namespace primlabel::bench {

// `what` names the PCL parts the benchmark needs, e.g. "PCL 1.13 (features, kdtree, search)".
inline std::string pcl_unavailable_reason(bool option_on, const std::string& what) {
  if (!option_on)
    return "this build was configured with -DPRIMLABEL_WITH_PCL=OFF; reconfigure with "
           "-DPRIMLABEL_WITH_PCL=ON and libpcl-dev installed";
  return what +
         " was not found when this build was configured (PRIMLABEL_WITH_PCL is ON): "
         "install libpcl-dev (PRIMLABEL_WITH_PCL=1 deploy/setup.sh build does) and "
         "reconfigure";
}

#ifdef PRIMLABEL_WITH_PCL_OPTION
inline std::string pcl_unavailable_reason(const std::string& what) {
  return pcl_unavailable_reason(PRIMLABEL_WITH_PCL_OPTION != 0, what);
}
#endif

}  // namespace primlabel::bench
