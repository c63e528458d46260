// Mirrored feature sets: the least-squares similarity of the sources onto the targets with reflection against
// without (Umeyama 1991 both ways, closed form in the plane); and the `mirror` option's horizontal flip of the
// features (sources x → width − x, gradient source frames mirrored) and of the texture.
#pragma once

#include <span>
#include <vector>

#include "texwarp/core/feature.hpp"
#include "texwarp/core/image.hpp"
#include "texwarp/proto/mirror_report.hpp"

namespace texwarp {

// Reflected residual below this fraction of the proper one: "mirrored". A true mirror image with noise leaves the
// proper fit's residual at about the set's own spread while the reflected one is the noise alone; sets that are no
// mirror image score near 1 (tests/core/mirror_test.cpp measures how rarely random sets fall below).
inline constexpr double kMirrorResidualRatio = 0.1;

struct MirrorFit {
  double proper_residual = 0.0;     // Σ|a·P + b − Q|², the best rotation + uniform scale + translation, px²
  double reflected_residual = 0.0;  // Σ|a·conj(P) + b − Q|², the best with a reflection, px²
  double residual_ratio = 1.0;      // reflected / proper (1 when both are 0 or fewer than 3 features)
  bool mirrored = false;            // at least 3 features and residual_ratio < kMirrorResidualRatio
};

// The fits of the features' positions (sources onto targets).
MirrorFit fit_mirror(std::span<const Feature> features);

// The features as seen in the texture flipped horizontally (x → width − x): each source mirrored, a gradient
// source frame's axis angle θ → π − θ (its scale kept). Targets are untouched.
std::vector<Feature> mirror_features(std::vector<Feature> features, double width);

// Flips the image horizontally in place: pixel (i, j) ↔ (width − 1 − i, j), the continuous x ↦ width − x.
void mirror_image(Image& image);

// What the report and the CLI suggest for a mirrored set.
inline constexpr const char* kMirrorSuggestion =
    "the targets look like a mirror image of the sources: set \"mirror\": true in the feature file (texwarp "
    "--mirror) to flip the texture horizontally first";

// The report's "mirror" section for features as the file gives them (before any mirroring); `applied`: the
// warp runs on the mirrored texture.
proto::MirrorReport mirror_report(std::span<const Feature> features, bool applied);

}  // namespace texwarp
