// Keeps gtrack_test_support a valid library when tests/support is empty.
