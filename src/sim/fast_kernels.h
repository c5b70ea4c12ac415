// Optimised replacements for the SUNDIALS serial-vector, dense-matrix and
// dense-LU kernels that CVODE calls on every step.
//
// Why: Debian 12's libsundials 6.4.1 is compiled without optimisation (-O0),
// so its generic kernels cost ~20 000 instructions per BDF step for an 8-state
// model, 6x more than our right-hand side. SUNDIALS lets a program install its
// own kernels through the ops tables of its objects; clones inherit them.
// The numbers are the same (same algorithms), only the code is optimised.
#pragma once

#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sundials/sundials_linearsolver.h>
#include <sundials/sundials_matrix.h>

namespace pneumaid::internal {

// Replaces the hot operations of a serial N_Vector (and of its future clones).
void InstallFastVectorKernels(N_Vector vector);

// Replaces copy and scale-add-identity of a dense SUNMatrix.
void InstallFastMatrixKernels(SUNMatrix matrix);

// A dense LU solver (partial pivoting) for square dense matrices of size n;
// owned by the caller (free with SUNLinSolFree). nullptr on allocation failure.
SUNLinearSolver NewFastDenseSolver(sunindextype n, SUNContext context);

}  // namespace pneumaid::internal
