// Pearson's chi-square goodness-of-fit test in the style of Mitsuba 3's chi2.py: cells with an
// expected count below a threshold are pooled (smallest first) until the pool reaches it, an
// observation in a cell of zero expected count is a failure (beyond `zero_cell_slack`, which a
// caller sets only where its quadrature can miss a sliver of support, and says why), and the
// p-value comes from the chi-square distribution with (cells after pooling - 1) degrees of
// freedom.
#pragma once
#include <string>
#include <vector>

namespace ett {

struct Chi2Result {
    double statistic = 0.0;
    int dof = 0;
    double p_value = 1.0;
    double alpha = 0.0;
    int pooled_cells = 0;             // input cells merged into pools
    double samples_in_zero_cells = 0; // observations where nothing was expected
    bool passed = false;
    std::string report; // summary and the worst cells, for the failure message
};

// observed and expected are counts over a grid of `width` x `height` cells (row-major), used
// only to name cells in the report.
Chi2Result chi2_test(const std::vector<double>& observed, const std::vector<double>& expected,
                     int width, int height, double alpha, double min_expected = 5.0,
                     double zero_cell_slack = 0.0);

// Per-test significance level keeping the family-wise rate at `alpha` over `tests` tests.
double sidak_alpha(double alpha, int tests);

// Writes observed, expected and (obs - exp) / sqrt(exp) as a 3-channel float image beside the
// test's scratch files; returns its path ("" when it could not).
std::string dump_histograms(const std::string& name, const std::vector<double>& observed,
                            const std::vector<double>& expected, int width, int height);

} // namespace ett
