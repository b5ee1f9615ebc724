// A user's program against an installed rsw: loads a shipped material through the
// installed headers, library and data, and prints its solidus and liquidus in degC.
#include "materials/material_library.hpp"

#include <iostream>

int main() {
  rsw::materials::MaterialLibrary::set_shipped_directory(MATERIALS_DIR);
  const rsw::materials::Material steel = rsw::materials::MaterialLibrary().load("DP1200");
  std::cout << "DP1200 solidus " << steel.solidus() << " liquidus " << steel.liquidus() << "\n";
  return 0;
}
