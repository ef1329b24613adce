// The source of pmg_test_pch: the target exists to build the tests' precompiled header
// (test/CMakeLists.txt, pmg_add_test). Nothing here is linked into a test.
