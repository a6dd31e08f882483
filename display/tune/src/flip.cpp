// LDR-FLIP (Andersson, Nilsson, Akenine-Möller, Oskarsson, Åström, Fairchild 2020, "FLIP: A
// Difference Evaluator for Alternating Images", HPG 2020), written from the paper's
// description. Two pipelines per pixel, combined as deltaE_c ^ (1 - deltaE_f):
//   colour:  sRGB -> linear RGB -> XYZ -> YCxCz; each opponent channel filtered with its
//            contrast sensitivity function (a sum of Gaussians in visual degrees); back to
//            linear RGB, clamped to the RGB cube; CIELAB; Hunt adjustment (a, b scaled by
//            0.01 L); HyAB distance; raised to qc = 0.7 and remapped so that errors below
//            pc x cmax take [0, pt] and the rest [pt, 1], cmax being the (powered) distance
//            between Hunt-adjusted green and blue, the largest in the cube.
//   feature: on the achromatic channel (Y / Yn), edges (first derivative of a Gaussian with
//            sd = 0.5 x 0.082 degrees) and points (second derivative), each kernel's positive
//            and negative weights normalised to +1 and -1; the larger of the two differences of
//            gradient magnitudes, divided by sqrt(2), raised to qf = 0.5.
// Image borders are extended by their edge pixels. Every filter is separable (a sum of
// separable Gaussians), so it runs as two 1D passes.
#include <rtwall/tune.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <string>

namespace rtwall {

namespace {

constexpr double kQc = 0.7, kPc = 0.4, kPt = 0.95, kQf = 0.5, kFeatureWidthDegrees = 0.082;

using Mat3 = std::array<std::array<double, 3>, 3>;

// Linear sRGB (D65) to XYZ, the exact rationals of the reference implementation.
constexpr Mat3 kRgbToXyz = {{{10135552.0 / 24577794, 8788810.0 / 24577794, 4435075.0 / 24577794},
                             {2613072.0 / 12288897, 8788810.0 / 12288897, 887015.0 / 12288897},
                             {1425312.0 / 73733382, 8788810.0 / 73733382, 70074185.0 / 73733382}}};

Mat3 inverse(const Mat3& m) {
    const double det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                       m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    Mat3 r{};
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            const int a = (j + 1) % 3, b = (j + 2) % 3, c = (i + 1) % 3, d = (i + 2) % 3;
            r[i][j] = (m[a][c] * m[b][d] - m[a][d] * m[b][c]) / det;
        }
    return r;
}

struct V3 {
    double x, y, z;
};

V3 mul(const Mat3& m, V3 v) {
    return {m[0][0] * v.x + m[0][1] * v.y + m[0][2] * v.z, m[1][0] * v.x + m[1][1] * v.y + m[1][2] * v.z,
            m[2][0] * v.x + m[2][1] * v.y + m[2][2] * v.z};
}

const Mat3& xyzToRgb() {
    static const Mat3 m = inverse(kRgbToXyz);
    return m;
}

// The reference white: XYZ of linear RGB (1, 1, 1).
const V3& white() {
    static const V3 w = mul(kRgbToXyz, {1, 1, 1});
    return w;
}

double srgbToLinear(double c) { return c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4); }

V3 xyzToYcxcz(V3 xyz) {
    const V3& w = white();
    const double x = xyz.x / w.x, y = xyz.y / w.y, z = xyz.z / w.z;
    return {116 * y - 16, 500 * (x - y), 200 * (y - z)};
}

V3 ycxczToXyz(V3 v) {
    const V3& w = white();
    const double y = (v.x + 16) / 116, x = v.y / 500 + y, z = y - v.z / 200;
    return {x * w.x, y * w.y, z * w.z};
}

double labF(double t) {
    constexpr double d = 6.0 / 29;
    return t > d * d * d ? std::cbrt(t) : t / (3 * d * d) + 4.0 / 29;
}

// Linear RGB -> CIELAB (D65 white as above) -> Hunt-adjusted (a, b scaled by 0.01 L).
V3 huntLab(V3 rgb) {
    const V3 xyz = mul(kRgbToXyz, rgb);
    const V3& w = white();
    const double fx = labF(xyz.x / w.x), fy = labF(xyz.y / w.y), fz = labF(xyz.z / w.z);
    const double l = 116 * fy - 16;
    return {l, 0.01 * l * 500 * (fx - fy), 0.01 * l * 200 * (fy - fz)};
}

double hyab(V3 a, V3 b) { return std::abs(a.x - b.x) + std::hypot(a.y - b.y, a.z - b.z); }

// One separable plane filter: 1D kernel along x, another along y, edges extended.
void filterSeparable(const std::vector<double>& in, std::vector<double>& out, std::vector<double>& tmp, int w, int h,
                     const std::vector<double>& kx, const std::vector<double>& ky) {
    const int rx = int(kx.size() / 2), ry = int(ky.size() / 2);
    tmp.assign(in.size(), 0.0);
    std::vector<double> row(size_t(w + 2 * rx));  // one row with its extended edges
    for (int y = 0; y < h; ++y) {
        const double* src = &in[size_t(y) * w];
        for (int x = -rx; x < w + rx; ++x) row[size_t(x + rx)] = src[std::clamp(x, 0, w - 1)];
        double* dst = &tmp[size_t(y) * w];
        for (size_t k = 0; k < kx.size(); ++k) {
            const double c = kx[k];
            const double* r = &row[k];
            for (int x = 0; x < w; ++x) dst[x] += c * r[x];
        }
    }
    out.assign(in.size(), 0.0);
    for (int y = 0; y < h; ++y)
        for (int k = -ry; k <= ry; ++k) {
            const double c = ky[size_t(k + ry)];
            const double* src = &tmp[size_t(std::clamp(y + k, 0, h - 1)) * w];
            double* dst = &out[size_t(y) * w];
            for (int x = 0; x < w; ++x) dst[x] += c * src[x];
        }
}

// The CSF of one opponent channel: a1 sqrt(pi / b1) exp(-pi^2 r^2 / b1) + a2 (...b2), r in
// degrees, normalised to sum 1 over the (2R + 1)^2 window. Each Gaussian term is separable,
// returned as its 1D profile and its weight in the normalised sum.
struct Csf {
    std::vector<double> g1, g2;
    double w1 = 0, w2 = 0;
};

Csf csf(double a1, double b1, double a2, double b2, double ppd, int radius) {
    Csf c;
    const double dx = 1.0 / ppd;
    double s1 = 0, s2 = 0;
    for (int i = -radius; i <= radius; ++i) {
        const double z = (i * dx) * (i * dx);
        c.g1.push_back(std::exp(-std::numbers::pi * std::numbers::pi * z / b1));
        c.g2.push_back(std::exp(-std::numbers::pi * std::numbers::pi * z / b2));
        s1 += c.g1.back();
        s2 += c.g2.back();
    }
    const double k1 = a1 * std::sqrt(std::numbers::pi / b1), k2 = a2 * std::sqrt(std::numbers::pi / b2);
    const double total = k1 * s1 * s1 + k2 * s2 * s2;  // the 2D kernel's sum
    c.w1 = k1 / total;
    c.w2 = k2 / total;
    return c;
}

// Edge (first derivative) or point (second derivative) detector along x; the y profile is the
// Gaussian. Positive weights of the 2D kernel sum to 1, negative ones to -1.
void featureKernels(double ppd, bool points, std::vector<double>& dx, std::vector<double>& g) {
    const double sd = 0.5 * kFeatureWidthDegrees * ppd;
    const int radius = int(std::ceil(3 * sd));
    dx.clear();
    g.clear();
    double gs = 0;
    for (int i = -radius; i <= radius; ++i) {
        const double e = std::exp(-double(i) * i / (2 * sd * sd));
        g.push_back(e);
        gs += e;
        dx.push_back(points ? (double(i) * i / (sd * sd) - 1) * e : -double(i) * e);
    }
    double pos = 0, neg = 0;
    for (double v : dx) (v > 0 ? pos : neg) += v;
    for (double& v : dx) v = v > 0 ? v / pos : v / -neg;
    for (double& v : g) v /= gs;
}

struct Planes {
    std::vector<double> c[3];
};

}  // namespace

std::vector<float> flipErrorMap(const Image& test, const Image& reference, double pixelsPerDegree) {
    if (test.width != reference.width || test.height != reference.height)
        throw InputError("FLIP: the images differ in size: " + std::to_string(test.width) + "x" +
                         std::to_string(test.height) + " against " + std::to_string(reference.width) + "x" +
                         std::to_string(reference.height));
    if (!(pixelsPerDegree > 0) || pixelsPerDegree > 10000)
        throw InputError("FLIP: pixels per degree must lie in (0, 10000], not " + std::to_string(pixelsPerDegree));
    const int w = test.width, h = test.height;
    const size_t n = size_t(w) * h;
    if (test.rgb.size() != n * 3 || reference.rgb.size() != n * 3)
        throw InputError("FLIP: an image's pixel buffer does not match its size");
    if (n == 0) return {};

    std::array<double, 256> lin{};
    for (int i = 0; i < 256; ++i) lin[size_t(i)] = srgbToLinear(i / 255.0);

    // The CSFs (the paper's Table 1 parameters); one radius for all, from the widest Gaussian.
    const double maxB = 0.04;
    const int radius = int(std::ceil(3 * std::sqrt(maxB / (2 * std::numbers::pi * std::numbers::pi)) * pixelsPerDegree));
    const Csf filters[3] = {csf(1, 0.0047, 0, 1e-5, pixelsPerDegree, radius),        // achromatic
                            csf(1, 0.0053, 0, 1e-5, pixelsPerDegree, radius),        // red-green
                            csf(34.1, 0.04, 13.5, 0.025, pixelsPerDegree, radius)};  // blue-yellow
    std::vector<double> edge, point, gauss, gaussPoint;
    featureKernels(pixelsPerDegree, false, edge, gauss);
    featureKernels(pixelsPerDegree, true, point, gaussPoint);

    // Per image: filtered colour as Hunt-adjusted L*a*b*, and the two feature magnitudes.
    auto pipeline = [&](const Image& img, std::vector<V3>& lab, std::vector<double>& edges, std::vector<double>& points) {
        Planes ycc;
        for (auto& p : ycc.c) p.resize(n);
        for (size_t i = 0; i < n; ++i) {
            const V3 v = xyzToYcxcz(mul(kRgbToXyz, {lin[img.rgb[3 * i]], lin[img.rgb[3 * i + 1]], lin[img.rgb[3 * i + 2]]}));
            ycc.c[0][i] = v.x;
            ycc.c[1][i] = v.y;
            ycc.c[2][i] = v.z;
        }
        Planes filtered;
        std::vector<double> a, tmp;
        for (int ch = 0; ch < 3; ++ch) {
            const Csf& f = filters[ch];
            filterSeparable(ycc.c[ch], filtered.c[ch], tmp, w, h, f.g1, f.g1);
            for (double& v : filtered.c[ch]) v *= f.w1;
            if (f.w2 != 0) {
                filterSeparable(ycc.c[ch], a, tmp, w, h, f.g2, f.g2);
                for (size_t i = 0; i < n; ++i) filtered.c[ch][i] += f.w2 * a[i];
            }
        }
        lab.resize(n);
        for (size_t i = 0; i < n; ++i) {
            V3 rgb = mul(xyzToRgb(), ycxczToXyz({filtered.c[0][i], filtered.c[1][i], filtered.c[2][i]}));
            rgb = {std::clamp(rgb.x, 0.0, 1.0), std::clamp(rgb.y, 0.0, 1.0), std::clamp(rgb.z, 0.0, 1.0)};
            lab[i] = huntLab(rgb);
        }
        // Features on the unfiltered achromatic channel, normalised to [0, 1]: (Y' + 16) / 116.
        std::vector<double>& y = ycc.c[0];
        for (double& v : y) v = (v + 16) / 116;
        std::vector<double> fx, fy;
        filterSeparable(y, fx, tmp, w, h, edge, gauss);
        filterSeparable(y, fy, tmp, w, h, gauss, edge);
        edges.resize(n);
        for (size_t i = 0; i < n; ++i) edges[i] = std::hypot(fx[i], fy[i]);
        filterSeparable(y, fx, tmp, w, h, point, gaussPoint);
        filterSeparable(y, fy, tmp, w, h, gaussPoint, point);
        points.resize(n);
        for (size_t i = 0; i < n; ++i) points[i] = std::hypot(fx[i], fy[i]);
    };
    std::vector<V3> labT, labR;
    std::vector<double> edgeT, edgeR, pointT, pointR;
    pipeline(test, labT, edgeT, pointT);
    pipeline(reference, labR, edgeR, pointR);

    const double cmax = std::pow(hyab(huntLab({0, 1, 0}), huntLab({0, 0, 1})), kQc);
    const double pccmax = kPc * cmax;
    std::vector<float> out(n);
    for (size_t i = 0; i < n; ++i) {
        const double e = std::pow(hyab(labT[i], labR[i]), kQc);
        const double dc = e < pccmax ? (kPt / pccmax) * e : kPt + (e - pccmax) / (cmax - pccmax) * (1 - kPt);
        const double df =
            std::pow(std::max(std::abs(edgeT[i] - edgeR[i]), std::abs(pointT[i] - pointR[i])) / std::numbers::sqrt2, kQf);
        out[i] = float(std::pow(dc, 1 - df));
    }
    return out;
}

double flipMean(const Image& test, const Image& reference, double pixelsPerDegree) {
    const std::vector<float> map = flipErrorMap(test, reference, pixelsPerDegree);
    double s = 0;
    for (float v : map) s += v;
    return map.empty() ? 0.0 : s / double(map.size());
}

}  // namespace rtwall
