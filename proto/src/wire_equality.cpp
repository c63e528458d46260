// The wire types' equality: each operator== their headers declare, defaulted here (member by member, C++20), so
// that the headers libtexwarp_client installs stay C++17 for plugin hosts while no comparison can miss a member.
#include "texwarp/proto/device_spec.hpp"
#include "texwarp/proto/gltf_selection_spec.hpp"
#include "texwarp/proto/input_location.hpp"
#include "texwarp/proto/job_report.hpp"
#include "texwarp/proto/job_spec.hpp"
#include "texwarp/proto/json_path.hpp"
#include "texwarp/proto/latency_stage.hpp"
#include "texwarp/proto/mesh_data_spec.hpp"
#include "texwarp/proto/mesh_flips_report.hpp"
#include "texwarp/proto/mirror_report.hpp"
#include "texwarp/proto/region_spec.hpp"
#include "texwarp/proto/surface_feature_spec.hpp"
#include "texwarp/proto/warp_spec.hpp"

namespace texwarp::proto {

bool operator==(const DeviceSpec&, const DeviceSpec&) = default;
bool operator==(const GltfSelectionSpec&, const GltfSelectionSpec&) = default;
bool operator==(const InputLocation&, const InputLocation&) = default;
bool TrajectoryReport::operator==(const TrajectoryReport&) const = default;
bool CertificateReport::operator==(const CertificateReport&) const = default;
bool WarpSetupReport::operator==(const WarpSetupReport&) const = default;
bool PrealignmentReport::operator==(const PrealignmentReport&) const = default;
bool DistortionReport::operator==(const DistortionReport&) const = default;
bool ClosestApproachReport::operator==(const ClosestApproachReport&) const = default;
bool FeatureResidualReport::operator==(const FeatureResidualReport&) const = default;
bool ResidualsReport::operator==(const ResidualsReport&) const = default;
bool JacobianReport::operator==(const JacobianReport&) const = default;
bool ImageInfoReport::operator==(const ImageInfoReport&) const = default;
bool SamplingReport::operator==(const SamplingReport&) const = default;
bool OutputImageReport::operator==(const OutputImageReport&) const = default;
bool MapReport::operator==(const MapReport&) const = default;
bool ImageJobReport::operator==(const ImageJobReport&) const = default;
bool ImageSizeReport::operator==(const ImageSizeReport&) const = default;
bool MeshCountsReport::operator==(const MeshCountsReport&) const = default;
bool RegionReport::operator==(const RegionReport&) const = default;
bool LscmReport::operator==(const LscmReport&) const = default;
bool UvQualityReport::operator==(const UvQualityReport&) const = default;
bool UvOptimizationReport::operator==(const UvOptimizationReport&) const = default;
bool UvUntanglingReport::operator==(const UvUntanglingReport&) const = default;
bool PlacedFeatureReport::operator==(const PlacedFeatureReport&) const = default;
bool TriangleReport::operator==(const TriangleReport&) const = default;
bool VertexReport::operator==(const VertexReport&) const = default;
bool MeshMappingReport::operator==(const MeshMappingReport&) const = default;
bool TimingsReport::operator==(const TimingsReport&) const = default;
bool JobReport::operator==(const JobReport&) const = default;
bool FeatureCountsReport::operator==(const FeatureCountsReport&) const = default;
bool CheckOptionsReport::operator==(const CheckOptionsReport&) const = default;
bool GradientCheckReport::operator==(const GradientCheckReport&) const = default;
bool CheckFailureReport::operator==(const CheckFailureReport&) const = default;
bool CheckReport::operator==(const CheckReport&) const = default;
bool operator==(const UdimTileSource&, const UdimTileSource&) = default;
bool operator==(const ImageSourceSpec&, const ImageSourceSpec&) = default;
bool operator==(const NamedImageSpec&, const NamedImageSpec&) = default;
bool operator==(const MeshSourceSpec&, const MeshSourceSpec&) = default;
bool operator==(const MeshJobSpec&, const MeshJobSpec&) = default;
bool operator==(const OutputSpec&, const OutputSpec&) = default;
bool operator==(const JobOptionsSpec&, const JobOptionsSpec&) = default;
bool operator==(const JobSpec&, const JobSpec&) = default;
bool operator==(const JsonPath&, const JsonPath&) = default;
bool StageTimings::operator==(const StageTimings&) const = default;
bool operator==(const MeshDataSpec&, const MeshDataSpec&) = default;
bool EmbeddingReport::operator==(const EmbeddingReport&) const = default;
bool FlippedFaceReport::operator==(const FlippedFaceReport&) const = default;
bool RefinementReport::operator==(const RefinementReport&) const = default;
bool SourcePointReport::operator==(const SourcePointReport&) const = default;
bool MirrorReport::operator==(const MirrorReport&) const = default;
bool operator==(const RegionSpec&, const RegionSpec&) = default;
bool operator==(const FaceTargetSpec&, const FaceTargetSpec&) = default;
bool operator==(const PointTargetSpec&, const PointTargetSpec&) = default;
bool operator==(const VertexTargetSpec&, const VertexTargetSpec&) = default;
bool operator==(const SurfaceFrameSpec&, const SurfaceFrameSpec&) = default;
bool operator==(const SurfaceFeatureSpec&, const SurfaceFeatureSpec&) = default;
bool operator==(const SurfaceFeatureSetSpec&, const SurfaceFeatureSetSpec&) = default;
bool operator==(const FrameSpec&, const FrameSpec&) = default;
bool operator==(const FeatureSpec&, const FeatureSpec&) = default;
bool operator==(const WarpSpec&, const WarpSpec&) = default;

}  // namespace texwarp::proto
