// The sparse Cholesky factorisation of the mesh solvers (LSCM's normal equations, the UV optimisation's global step):
// CHOLMOD's LLᵀ (SuiteSparse, libsuitesparse-dev) through Eigen's CholmodSupport, in CHOLMOD's automatic mode:
// supernodal where the factor's flops per non-zero make it pay (large regions; the supernodes run on BLAS, OpenBLAS
// where it is installed: scripts/setup.sh), simplicial otherwise. On a 180 000-face region with pins moved ±60 px the
// optimisation took 106 s with Eigen's simplicial factor and 42 s with this; a 1 804-face one as fast as before.
// The lower triangle is read.
#pragma once

#include <Eigen/CholmodSupport>
#include <Eigen/Sparse>

namespace texwarp::mesh {

class SparseCholesky : public Eigen::CholmodDecomposition<Eigen::SparseMatrix<double>, Eigen::Lower> {
 public:
  SparseCholesky() { setMode(Eigen::CholmodAuto); }
  explicit SparseCholesky(const Eigen::SparseMatrix<double>& matrix) {
    setMode(Eigen::CholmodAuto);
    compute(matrix);
  }
};

}  // namespace texwarp::mesh
