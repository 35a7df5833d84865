// tinyobjloader's implementation, compiled into the OBJ fuzz target with its sanitizers and
// coverage (it takes precedence over the prebuilt shared library).
#define TINYOBJLOADER_IMPLEMENTATION
#include <tiny_obj_loader.h>
