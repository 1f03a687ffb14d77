// crackvis-hdf5-worker: runs crackvis-data's HDF5 calls in a process of its
// own, so that a libhdf5 fault on a corrupt file ends only this process.
#include <crackvis/dataservice_service/hdf5_worker_main.hpp>

int main(int argc, char** argv) {
  return crackvis::dataservice::hdf5WorkerMain(argc, argv);
}
