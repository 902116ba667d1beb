// MPI for `pmfrag sweep` only (Open MPI from Debian). A process takes part only when mpirun started it
// (it finds mpirun's environment); otherwise, and in builds without MPI, size() is 1 and nothing is called.
#pragma once

#include <functional>

namespace pmfrag::app {

class MpiWorld {
 public:
  MpiWorld();   ///< MPI_Init when launched by mpirun (and the build has MPI)
  ~MpiWorld();  ///< MPI_Finalize
  MpiWorld(const MpiWorld&) = delete;
  MpiWorld& operator=(const MpiWorld&) = delete;
  int rank() const { return rank_; }
  int size() const { return size_; }
  /// Ranks on this node (for sharing its cores), from mpirun's environment.
  int local_size() const { return local_size_; }

  /// Dynamic hand-out of case numbers 0..count-1: every rank calls this with the same count and runs `work`
  /// for each number it is given, until none is left; rank 0 runs cases too (on a thread) while it serves
  /// the others' requests. Returns after every rank has finished (a barrier).
  void distribute(int count, const std::function<void(int)>& work);
  /// Waits for every rank (without spinning a core).
  void barrier();

 private:
  int rank_ = 0, size_ = 1, local_size_ = 1;
  bool active_ = false;
};

}  // namespace pmfrag::app
