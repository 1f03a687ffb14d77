// The main of crackvis-hdf5-worker, the program in which crackvis-data
// makes every HDF5 call (see hdf5_workers.hpp in the service's sources).
// crackvis-data starts it with its socket on descriptor 3 and the shared
// piece buffer on 4; arguments: the data root and crackvis-data's pid.
#pragma once

namespace crackvis::dataservice {

int hdf5WorkerMain(int argc, char** argv);

}  // namespace crackvis::dataservice
