// A program that does nothing: linked with tools/cpu_check.cpp and built for SSE4a
// (tests/tools/CMakeLists.txt), it shows what rsw does on a processor without an
// extension it was built for.
int main() { return 0; }
