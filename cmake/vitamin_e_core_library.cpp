// libvitamin_e.so (cmake/export.cmake): the core modules' objects, linked whole into one
// shared library for other packages. This file only gives the target a source.
namespace vitamin_e {
const char* libraryName() { return "vitamin_e"; }
}  // namespace vitamin_e
