#pragma once
// Reading the PEM files of gRPC's TLS credentials, shared by the server and the client.

#include <string>

namespace objmap {

/// The text of the PEM file at `path`; false with "<path>: cannot read the <what> (a PEM file)"
/// when it cannot be read or holds no PEM block.
[[nodiscard]] bool ReadPemFile(const std::string& path, const char* what, std::string* pem,
                               std::string* why);

}  // namespace objmap
