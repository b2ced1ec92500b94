// tri_version.cpp -- the CGAL version libiirtri was built against, for `iird --version`.
#include <CGAL/version.h>

extern "C" const char *iir_tri_cgal_version(void)
{
    return CGAL_VERSION_STR;
}
