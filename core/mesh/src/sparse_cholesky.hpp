// The sparse Cholesky factorisation of the mesh solvers (LSCM's normal equations, the UV optimisation's global step):
// CHOLMOD's supernodal LLᵀ (SuiteSparse, libsuitesparse-dev) through Eigen's CholmodSupport. Its supernodes run on
// BLAS (OpenBLAS where it is installed: scripts/setup.sh), several times faster than Eigen's simplicial factors on
// large meshes (a 180 000-face region's optimisation: 96 s → 36 s with OpenBLAS). The lower triangle is read.
#pragma once

#include <Eigen/CholmodSupport>
#include <Eigen/Sparse>

namespace texwarp::mesh {

using SparseCholesky = Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>, Eigen::Lower>;

}  // namespace texwarp::mesh
