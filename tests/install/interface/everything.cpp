// Every public header (the umbrella header): its compile line is what deflex::deflex hands a consumer.
#include "deflex/deflex.hpp"

int main() { return deflex::kVersionMinor >= 2 ? 0 : 1; }
