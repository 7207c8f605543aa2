// polyheal sha256: the FIPS 180-2 example vectors (one block, two blocks by
// padding, many blocks) and a file hashed as its bytes.
#include <catch2/catch.hpp>

#include <string>

#include "polyheal/io/sha256.h"
#include "polyheal/mesh/errors.h"
#include "support/builders.h"

using namespace polyheal;

TEST_CASE("sha256: standard vectors", "[sha256]") {
  CHECK(sha256_hex("") == "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  CHECK(sha256_hex("abc") == "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  // 56 bytes: the length no longer fits the first block.
  CHECK(sha256_hex("abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq") ==
        "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
  CHECK(sha256_hex(std::string(1000000, 'a')) == "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");
}

TEST_CASE("sha256: a file is hashed as its bytes, a missing file is an input error", "[sha256]") {
  const std::string p = test::scratch("sha_abc.bin");
  test::write_bytes(p, "abc");
  CHECK(sha256_file(p) == sha256_hex("abc"));
  CHECK_THROWS_AS(sha256_file(test::scratch("sha_none.bin")), InputError);
}
