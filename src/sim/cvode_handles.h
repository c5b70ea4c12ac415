// RAII owners for the SUNDIALS objects the simulator uses. Destruction order
// matters: the context must outlive everything created in it, so hold it first.
#pragma once

#include <cvodes/cvodes.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

#include <memory>
#include <stdexcept>
#include <type_traits>
#include <utility>

namespace pneumaid::internal {

struct ContextDeleter {
  void operator()(SUNContext context) const { SUNContext_Free(&context); }
};
struct VectorDeleter {
  void operator()(N_Vector vector) const { N_VDestroy(vector); }
};
struct MatrixDeleter {
  void operator()(SUNMatrix matrix) const { SUNMatDestroy(matrix); }
};
struct LinearSolverDeleter {
  void operator()(SUNLinearSolver solver) const { SUNLinSolFree(solver); }
};
struct CvodeDeleter {
  void operator()(void* memory) const { CVodeFree(&memory); }
};

using ContextPtr = std::unique_ptr<std::remove_pointer_t<SUNContext>, ContextDeleter>;
using VectorPtr = std::unique_ptr<std::remove_pointer_t<N_Vector>, VectorDeleter>;
using MatrixPtr = std::unique_ptr<std::remove_pointer_t<SUNMatrix>, MatrixDeleter>;
using LinearSolverPtr =
    std::unique_ptr<std::remove_pointer_t<SUNLinearSolver>, LinearSolverDeleter>;
using CvodePtr = std::unique_ptr<void, CvodeDeleter>;

// An owned N_VCloneVectorArray (the sensitivity vectors).
class VectorArray {
 public:
  VectorArray() = default;
  VectorArray(N_Vector* vectors, int count) : vectors_(vectors), count_(count) {}
  VectorArray(const VectorArray&) = delete;
  VectorArray& operator=(const VectorArray&) = delete;
  VectorArray& operator=(VectorArray&& other) noexcept {
    std::swap(vectors_, other.vectors_);
    std::swap(count_, other.count_);
    return *this;
  }
  ~VectorArray() {
    if (vectors_ != nullptr) N_VDestroyVectorArray(vectors_, count_);
  }
  N_Vector* get() const { return vectors_; }

 private:
  N_Vector* vectors_ = nullptr;
  int count_ = 0;
};

// Thrown only while setting the solver up (allocation failures), never from a
// callback; Simulate converts it into a failed summary.
class SundialsSetupError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

inline void CheckFlag(int flag, const char* call) {
  if (flag < 0) {
    throw SundialsSetupError(std::string(call) + " failed with flag " + std::to_string(flag));
  }
}

template <typename Pointer>
Pointer CheckAllocated(Pointer pointer, const char* call) {
  if (!pointer) throw SundialsSetupError(std::string(call) + " returned null");
  return pointer;
}

}  // namespace pneumaid::internal
