// The translation unit that compiles the tests' precompiled header
// (tests/CMakeLists.txt: pneumaid_test_pch).
