# cmake -DMESSAGE=... -P fail_with_message.cmake: fails (exit 1) printing MESSAGE; a test that
# stands in for tests that cannot run on this host.
message(FATAL_ERROR "${MESSAGE}")
