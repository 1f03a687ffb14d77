// The per-user credentials moved to crackvis::rpc_server
// (<crackvis/rpc/credentials.hpp>), shared by both servers. These names stay
// for crackvis-data's main until it includes the new header.
#pragma once

#include <crackvis/rpc/credentials.hpp>

namespace crackvis::dataservice {

using rpc::generateToken;
using rpc::hashSecret;
using rpc::hashToken;
using rpc::kDefaultHashIterations;

}  // namespace crackvis::dataservice
