// The program that builds the test programs' shared precompiled header (see tests/CMakeLists.txt):
// an executable like them, so that its header is compiled with the same flags (-fPIE). It does
// nothing.
int main() { return 0; }
