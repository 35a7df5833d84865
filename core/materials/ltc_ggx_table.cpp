#include "core/materials/ltc_ggx_table.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace penumbra {
namespace {

// The generated table: kGgxLtcTableSize^2 cells, row-major (row = roughness index).
#include "core/materials/data/ggx_ltc_table.inc"

static_assert(kGgxLtcTable.size() == size_t(kGgxLtcTableSize * kGgxLtcTableSize),
              "the generated table does not match kGgxLtcTableSize: rerun tools/ltc_fit");

// Position in grid units, clamped to the grid, split into a cell index and a fraction.
void grid_position(double t, int* index, double* fraction) {
  double position = std::clamp(t, 0.0, 1.0) * (kGgxLtcTableSize - 1);
  int i = std::min(int(position), kGgxLtcTableSize - 2);
  *index = i;
  *fraction = position - i;
}

}  // namespace

double ggx_ltc_table_alpha(int row) {
  double roughness = double(row) / (kGgxLtcTableSize - 1);
  return std::max(roughness * roughness, kGgxLtcMinAlpha);
}

double ggx_ltc_table_cos_theta(int column) {
  double x = double(column) / (kGgxLtcTableSize - 1);
  return std::max(1.0 - x * x, kGgxLtcMinCosTheta);
}

const GgxLtcCell& ggx_ltc_table_cell(int row, int column) {
  row = std::clamp(row, 0, kGgxLtcTableSize - 1);
  column = std::clamp(column, 0, kGgxLtcTableSize - 1);
  return kGgxLtcTable[size_t(row * kGgxLtcTableSize + column)];
}

Matrix3 ggx_ltc_inverse_matrix(double inverse_00, double inverse_02, double inverse_20,
                               double inverse_22) {
  Matrix3 inverse_matrix;
  inverse_matrix.m = {inverse_00, 0, inverse_02, 0, 1, 0, inverse_20, 0, inverse_22};
  return inverse_matrix;
}

GgxLtc ggx_ltc(double alpha, double cos_theta_o) {
  // Bilinear interpolation in (sqrt(alpha), sqrt(1 - cos theta_o)).
  int row, column;
  double a, b;
  grid_position(std::sqrt(std::max(alpha, 0.0)), &row, &a);
  grid_position(std::sqrt(std::max(0.0, 1.0 - std::min(cos_theta_o, 1.0))), &column, &b);
  const GgxLtcCell& c00 = ggx_ltc_table_cell(row, column);
  const GgxLtcCell& c01 = ggx_ltc_table_cell(row, column + 1);
  const GgxLtcCell& c10 = ggx_ltc_table_cell(row + 1, column);
  const GgxLtcCell& c11 = ggx_ltc_table_cell(row + 1, column + 1);
  auto blend = [&](double GgxLtcCell::*field) {
    return (1 - a) * ((1 - b) * c00.*field + b * c01.*field) +
           a * ((1 - b) * c10.*field + b * c11.*field);
  };
  Matrix3 inverse_matrix =
      ggx_ltc_inverse_matrix(blend(&GgxLtcCell::inverse_00), blend(&GgxLtcCell::inverse_02),
                             blend(&GgxLtcCell::inverse_20), blend(&GgxLtcCell::inverse_22));
  GgxLtc result;
  result.ltc = LinearlyTransformedCosine(inverse(inverse_matrix));
  result.albedo = blend(&GgxLtcCell::albedo);
  result.fresnel = blend(&GgxLtcCell::fresnel);
  return result;
}

}  // namespace penumbra
