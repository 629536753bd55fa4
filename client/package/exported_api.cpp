// librobodiff_client.so is made of the robodiff_client archive, linked in whole; this
// file only gives the shared library a translation unit of its own.
#include "robodiff/client/client.hpp"
