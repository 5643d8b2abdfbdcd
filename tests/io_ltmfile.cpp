// ltm.npz (io/LtmFile.h) and CsrMatrix (io/CsrMatrix.h): round trips, scipy interoperability
// in both directions, corrupt files, atomic writes.
//
// The scipy checks run /usr/bin/python3 (the `python3` on PATH may be another interpreter); they
// are skipped, with the reason, when it cannot import scipy.sparse.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "tests/TestSupport.h"
#include "io/CsrMatrix.h"
#include "io/LtmFile.h"

namespace fs = std::filesystem;
using ltm::CsrMatrix;

namespace {

const char* kPython = "/usr/bin/python3";

// A fresh folder `dir` per test, removed afterwards (ignoring a failure to remove it).
class LtmFileTest : public ltm::test::LenientTempDirTest {};

using ltm::test::message_of;
using ltm::test::slurp;
using ltm::test::spit;

// Runs a Python script with /usr/bin/python3; returns its stdout (stderr goes to the test log).
std::string run_python(const std::string& script_path, const std::string& script, int* status) {
    spit(script_path, script);
    const std::string cmd = std::string(kPython) + " '" + script_path + "'";
    FILE* p = ::popen(cmd.c_str(), "r");
    if (!p) {
        *status = -1;
        return {};
    }
    std::string out;
    char buf[65536];
    size_t n;
    while ((n = std::fread(buf, 1, sizeof buf, p)) > 0) out.append(buf, n);
    *status = ::pclose(p);
    return out;
}

// Empty if /usr/bin/python3 has scipy.sparse, else why not.
const std::string& scipy_missing() {
    static const std::string reason = [] {
        if (::access(kPython, X_OK) != 0) return std::string(kPython) + " does not exist";
        const std::string cmd = std::string(kPython) + " -c 'import scipy.sparse, numpy' > /dev/null 2>&1";
        if (std::system(cmd.c_str()) != 0) return std::string(kPython) + " cannot import scipy.sparse";
        return std::string();
    }();
    return reason;
}
#define REQUIRE_SCIPY()                                          \
    do {                                                         \
        if (!scipy_missing().empty()) LTM_INTEROP_SKIP() << scipy_missing(); \
    } while (0)

std::vector<std::string> lines_of(const std::string& s) {
    std::vector<std::string> out;
    std::istringstream is(s);
    std::string line;
    while (std::getline(is, line)) out.push_back(line);
    return out;
}

// The exact value of a float in Python's float.hex() notation, e.g. 0x1.8000000000000p-1.
std::string py_hex(float f) {
    const double d = f;
    if (d == 0.0) return std::signbit(d) ? "-0x0.0p+0" : "0x0.0p+0";
    int e = 0;
    const double m = std::frexp(std::fabs(d), &e);  // d = m 2^e, m in [0.5, 1)
    // Python normalises to 1.xxx p(e-1) with 13 hex digits of fraction.
    const double frac = m * 2.0 - 1.0;
    const auto bits = static_cast<unsigned long long>(std::ldexp(frac, 52));
    char buf[64];
    std::snprintf(buf, sizeof buf, "%s0x1.%013llxp%+d", d < 0 ? "-" : "", bits, e - 1);
    return buf;
}

bool same(const CsrMatrix& a, const CsrMatrix& b) { return bit_identical(a, b); }

CsrMatrix small_matrix() {
    // [[0, 0, 0, 0, 0],
    //  [1.5, 0, -2, 0, 0.1],
    //  [0, 0, 0, 0, 0],
    //  [0, 3e-39, 0, 0, 0],   (a float32 denormal)
    //  [0, 0, 0, 0, 0]]
    CsrMatrix m;
    m.rows = 5;
    m.cols = 5;
    m.indptr = {0, 0, 3, 3, 4, 4};
    m.indices = {0, 2, 4, 1};
    m.data = {1.5f, -2.0f, 0.1f, 3e-39f};
    return m;
}

// rows x cols with a random number of nonzeros per row (about a third of the rows empty).
CsrMatrix random_matrix(std::int64_t rows, std::int64_t cols, int max_per_row, unsigned seed) {
    std::mt19937 rng(seed);
    CsrMatrix m;
    m.rows = rows;
    m.cols = cols;
    m.indptr.push_back(0);
    std::uniform_real_distribution<float> value(-1.0f, 1.0f);
    for (std::int64_t r = 0; r < rows; ++r) {
        const int k = static_cast<int>(rng() % static_cast<unsigned>(max_per_row + 1)) - max_per_row / 3;
        std::vector<std::int32_t> cs;
        for (int i = 0; i < k; ++i) cs.push_back(static_cast<std::int32_t>(rng() % static_cast<unsigned>(cols)));
        std::sort(cs.begin(), cs.end());
        cs.erase(std::unique(cs.begin(), cs.end()), cs.end());
        for (std::int32_t c : cs) {
            m.indices.push_back(c);
            m.data.push_back(value(rng));
        }
        m.indptr.push_back(static_cast<std::int64_t>(m.indices.size()));
    }
    return m;
}

// Offset of the central directory header of entry `name` in a ZIP file's bytes.
std::size_t central_header_of(const std::string& zip, const std::string& name) {
    std::size_t pos = 0;
    while ((pos = zip.find("PK\x01\x02", pos)) != std::string::npos) {
        if (zip.compare(pos + 46, name.size(), name) == 0) return pos;
        pos += 4;
    }
    return std::string::npos;
}

// The message of what f throws while the process may write files of at most 4096 bytes (the
// write fails half-way with EFBIG, SIGXFSZ ignored), or "" if it throws nothing.
template <class F>
std::string message_under_file_size_limit(F&& f) {
    struct sigaction ignore {}, previous {};
    ignore.sa_handler = SIG_IGN;
    ::sigaction(SIGXFSZ, &ignore, &previous);
    rlimit saved{};
    ::getrlimit(RLIMIT_FSIZE, &saved);
    rlimit small = saved;
    small.rlim_cur = 4096;
    if (::setrlimit(RLIMIT_FSIZE, &small) != 0) {
        ::sigaction(SIGXFSZ, &previous, nullptr);
        return "setrlimit failed";
    }
    const std::string msg = message_of(f);
    ::setrlimit(RLIMIT_FSIZE, &saved);
    ::sigaction(SIGXFSZ, &previous, nullptr);
    return msg;
}

}  // namespace

// ----- CsrMatrix -----

TEST(CsrMatrix, CheckAcceptsValidMatrices) {
    EXPECT_EQ(small_matrix().check(), "");
    EXPECT_EQ(CsrMatrix::zeros(0, 0).check(), "");
    EXPECT_EQ(CsrMatrix::zeros(3, 7).check(), "");
    EXPECT_EQ(random_matrix(100, 50, 10, 1).check(), "");
}

TEST(CsrMatrix, CheckNamesEachProblem) {
    auto broken = [](auto edit) {
        CsrMatrix m = small_matrix();
        edit(m);
        return m.check();
    };
    EXPECT_NE(broken([](CsrMatrix& m) { m.indptr.pop_back(); }).find("indptr has 5 entries, expected rows + 1 = 6"),
              std::string::npos);
    EXPECT_NE(broken([](CsrMatrix& m) { m.indptr[0] = 1; }).find("indptr[0] = 1"), std::string::npos);
    EXPECT_NE(broken([](CsrMatrix& m) { m.indptr[2] = -1; }).find("decreases at row 1"), std::string::npos);
    EXPECT_NE(broken([](CsrMatrix& m) { m.indptr[5] = 3; }).find("number of nonzeros 4"), std::string::npos);
    EXPECT_NE(broken([](CsrMatrix& m) { m.indices[1] = 5; }).find("column index 5 of nonzero 1 (row 1) is outside [0, 5)"),
              std::string::npos);
    EXPECT_NE(broken([](CsrMatrix& m) { m.indices[3] = -1; }).find("column index -1"), std::string::npos);
    EXPECT_NE(broken([](CsrMatrix& m) { m.indices[1] = 0; }).find("not strictly increasing"), std::string::npos);
    EXPECT_NE(broken([](CsrMatrix& m) { std::swap(m.indices[1], m.indices[2]); }).find("row 1"), std::string::npos);
    EXPECT_NE(broken([](CsrMatrix& m) { m.data[2] = std::nanf(""); }).find("nonzero 2"), std::string::npos);
    EXPECT_NE(broken([](CsrMatrix& m) { m.data[0] = -std::numeric_limits<float>::infinity(); }).find("not a finite"),
              std::string::npos);
    EXPECT_NE(broken([](CsrMatrix& m) { m.data.pop_back(); }).find("indices has 4 entries but data has 3"),
              std::string::npos);
    EXPECT_NE(broken([](CsrMatrix& m) { m.cols = -1; }).find("negative shape"), std::string::npos);
}

TEST(CsrMatrix, MultiplyKnownMatrix) {
    // [[1, 0, 2], [0, 0, 0], [0.5, -4, 0.25]] x [8, 2, -1] = [6, 0, -4.25]
    CsrMatrix m;
    m.rows = 3;
    m.cols = 3;
    m.indptr = {0, 2, 2, 5};
    m.indices = {0, 2, 0, 1, 2};
    m.data = {1.0f, 2.0f, 0.5f, -4.0f, 0.25f};
    ASSERT_EQ(m.check(), "");
    const float x[3] = {8.0f, 2.0f, -1.0f};
    double y[3] = {99.0, 99.0, 99.0};  // overwritten, not accumulated into
    m.multiply(x, y);
    EXPECT_EQ(y[0], 6.0);
    EXPECT_EQ(y[1], 0.0);
    EXPECT_EQ(y[2], -4.25);
}

TEST(CsrMatrix, MultiplyAccumulatesInDoubleInIndexOrder) {
    // 1 + 2^-30 - 1 is 2^-30 in double (it would be 0 in float), and the order is the index order.
    CsrMatrix m;
    m.rows = 1;
    m.cols = 3;
    m.indptr = {0, 3};
    m.indices = {0, 1, 2};
    m.data = {1.0f, std::ldexp(1.0f, -30), -1.0f};
    const float x[3] = {1.0f, 1.0f, 1.0f};
    double y = 0;
    m.multiply(x, &y);
    EXPECT_EQ(y, std::ldexp(1.0, -30));

    const CsrMatrix r = random_matrix(500, 40, 12, 7);
    std::vector<float> xv(40);
    for (int i = 0; i < 40; ++i) xv[static_cast<std::size_t>(i)] = 0.1f * static_cast<float>(i) - 1.3f;
    std::vector<double> y1(500), y2(500);
    r.multiply(xv.data(), y1.data());
    for (std::int64_t row = 0; row < r.rows; ++row) {
        double s = 0;
        for (auto i = r.indptr[static_cast<std::size_t>(row)]; i < r.indptr[static_cast<std::size_t>(row) + 1]; ++i)
            s += double(r.data[static_cast<std::size_t>(i)]) * double(xv[static_cast<std::size_t>(r.indices[static_cast<std::size_t>(i)])]);
        y2[static_cast<std::size_t>(row)] = s;
    }
    EXPECT_EQ(y1, y2);
}

// ----- round trips -----

TEST_F(LtmFileTest, RoundTripHandBuiltMatrices) {
    CsrMatrix one;
    one.rows = one.cols = 1;
    one.indptr = {0, 1};
    one.indices = {0};
    one.data = {0.75f};
    CsrMatrix extremes = CsrMatrix::zeros(2, 3);
    extremes.indptr = {0, 3, 4};
    extremes.indices = {0, 1, 2, 2};
    extremes.data = {-0.0f, std::numeric_limits<float>::max(), std::numeric_limits<float>::denorm_min(),
                     -std::numeric_limits<float>::min()};
    const std::vector<std::pair<std::string, CsrMatrix>> cases = {
        {"small with empty rows", small_matrix()},
        {"all empty 3x7", CsrMatrix::zeros(3, 7)},
        {"0x0", CsrMatrix::zeros(0, 0)},
        {"1x1", one},
        {"extreme values", extremes},
        {"70000 rows", random_matrix(70000, 300, 6, 42)},
        {"wide 3 x 2^31", [] {
             CsrMatrix w = CsrMatrix::zeros(3, std::int64_t(1) << 31);
             w.indptr = {0, 1, 1, 2};
             w.indices = {0, std::numeric_limits<std::int32_t>::max()};
             w.data = {1.0f, 2.0f};
             return w;
         }()},
    };
    for (const auto& [name, m] : cases) {
        SCOPED_TRACE(name);
        ASSERT_EQ(m.check(), "");
        const std::string p = path("ltm.npz");
        ltm::write_ltm_npz(p, m);
        const CsrMatrix back = ltm::read_ltm_npz(p);
        EXPECT_TRUE(same(m, back)) << "rows " << back.rows << " cols " << back.cols << " nnz " << back.nnz();
    }
    EXPECT_EQ(listing(), std::vector<std::string>{"ltm.npz"});  // no temporaries left
}

TEST_F(LtmFileTest, RoundTripOptions) {
    const CsrMatrix m = random_matrix(3000, 500, 9, 3);
    for (int level : {0, 1, 3}) {
        SCOPED_TRACE("level " + std::to_string(level));
        ltm::NpzWriteOptions o;
        o.compression_level = level;
        ltm::write_ltm_npz(path("o.npz"), m, o);
        EXPECT_TRUE(same(m, ltm::read_ltm_npz(path("o.npz"))));
        EXPECT_EQ(slurp(path("o.npz")).find("PK\x06\x06"), std::string::npos);  // small: no ZIP64 end record
    }
}

TEST_F(LtmFileTest, OutputIsDeterministic) {
    const CsrMatrix m = random_matrix(2000, 100, 8, 9);
    ltm::write_ltm_npz(path("a.npz"), m);
    ltm::write_ltm_npz(path("b.npz"), m);
    EXPECT_EQ(slurp(path("a.npz")), slurp(path("b.npz")));
}

// ----- streaming (LtmFileStream) -----

namespace {

// Rows [r0, r1) of m as a matrix of their own.
CsrMatrix row_block(const CsrMatrix& m, std::int64_t r0, std::int64_t r1) {
    CsrMatrix b;
    b.rows = r1 - r0;
    b.cols = m.cols;
    const auto from = m.indptr[static_cast<size_t>(r0)], to = m.indptr[static_cast<size_t>(r1)];
    for (std::int64_t r = r0; r <= r1; ++r) b.indptr.push_back(m.indptr[static_cast<size_t>(r)] - from);
    b.indices.assign(m.indices.begin() + from, m.indices.begin() + to);
    b.data.assign(m.data.begin() + from, m.data.begin() + to);
    return b;
}

}  // namespace

TEST_F(LtmFileTest, StreamedFileIsByteIdenticalToTheWholeMatrixsFile) {
    const std::vector<std::pair<std::string, CsrMatrix>> cases = {
        {"small with empty rows", small_matrix()},
        {"all empty 3x7", CsrMatrix::zeros(3, 7)},
        {"0x0", CsrMatrix::zeros(0, 0)},
        {"70000 rows", random_matrix(70000, 300, 6, 42)},
    };
    for (int level : {0, 1, 3}) {
        ltm::NpzWriteOptions o;
        o.compression_level = level;
        for (const auto& [name, m] : cases) {
            ltm::write_ltm_npz(path("whole.npz"), m, o);
            const std::string whole = slurp(path("whole.npz"));
            // Blocks of one row, of 7, of uneven random sizes (zero-row blocks among them), all at once.
            for (int split : {1, 7, -1, 0}) {
                SCOPED_TRACE(name + ", level " + std::to_string(level) + ", split " + std::to_string(split));
                ltm::LtmFileStream stream(path("streamed.npz"), m.rows, m.cols, o);
                std::mt19937 rng(5);
                std::int64_t r = 0;
                do {  // at least one block, so a matrix of no rows gets an empty one
                    const std::int64_t n = split == 0 ? m.rows : split > 0 ? split : static_cast<std::int64_t>(rng() % 50);
                    const std::int64_t r1 = std::min(m.rows, r + n);
                    stream.append(row_block(m, r, r1));
                    r = r1;
                } while (r < m.rows);
                EXPECT_EQ(stream.rows_written(), m.rows);
                EXPECT_EQ(stream.nnz(), m.nnz());
                // The spill files are unnamed: the folder shows nothing of them, before or after.
                EXPECT_EQ(listing(), std::vector<std::string>{"whole.npz"});
                stream.commit();
                EXPECT_EQ(slurp(path("streamed.npz")), whole);
                EXPECT_EQ(listing(), (std::vector<std::string>{"streamed.npz", "whole.npz"}));
                fs::remove(path("streamed.npz"));
            }
        }
    }
}

TEST_F(LtmFileTest, StreamRefusesBadBlocksAndAnUnfinishedStreamWritesNothing) {
    const CsrMatrix m = small_matrix();  // 5 x 5
    const std::string target = path("ltm.npz");
    {
        ltm::LtmFileStream stream(target, m.rows, m.cols);
        std::string msg = message_of([&] { stream.append(CsrMatrix::zeros(2, 4)); });
        EXPECT_NE(msg.find("cannot write LTM file '" + target + "': a block of 4 columns for a matrix of 5"),
                  std::string::npos)
            << msg;
        CsrMatrix broken = row_block(m, 0, 3);
        broken.indices[0] = 7;
        msg = message_of([&] { stream.append(broken); });
        EXPECT_NE(msg.find("the block at row 0 is invalid"), std::string::npos) << msg;
        stream.append(row_block(m, 0, 3));
        msg = message_of([&] { stream.append(row_block(m, 0, 3)); });
        EXPECT_NE(msg.find("rows 3 + 3 exceed the matrix's 5"), std::string::npos) << msg;
        msg = message_of([&] { stream.commit(); });
        EXPECT_NE(msg.find("only 3 of 5 rows were given"), std::string::npos) << msg;
    }  // destroyed uncommitted
    EXPECT_TRUE(listing().empty());
    const std::string nowhere = path("no/such/folder/ltm.npz");
    const std::string msg = message_of([&] { ltm::LtmFileStream s(nowhere, 1, 1); });
    EXPECT_NE(msg.find("cannot write LTM file '" + nowhere + "': cannot create a spill file in folder '" +
                       path("no/such/folder") + "'"),
              std::string::npos)
        << msg;
}

TEST_F(LtmFileTest, AFailedStreamedCommitLeavesTheTargetUntouched) {
    const std::string target = path("ltm.npz");
    ltm::write_ltm_npz(target, small_matrix());
    const std::string before = slurp(target);
    const CsrMatrix big = random_matrix(20000, 1000, 10, 1);
    ltm::LtmFileStream stream(target, big.rows, big.cols);
    stream.append(big);
    const std::string msg = message_under_file_size_limit([&] { stream.commit(); });
    EXPECT_NE(msg.find("cannot write LTM file '" + target + "'"), std::string::npos) << msg;
    EXPECT_NE(msg.find("File too large"), std::string::npos) << msg;
    EXPECT_EQ(slurp(target), before);
    EXPECT_EQ(listing(), std::vector<std::string>{"ltm.npz"});
}

// ----- scipy interoperability -----

TEST_F(LtmFileTest, ScipyLoadsOurFile) {
    REQUIRE_SCIPY();
    const CsrMatrix m = small_matrix();
    {
        ltm::write_ltm_npz(path("ltm.npz"), m);
        int status = 0;
        const std::string out = run_python(path("load.py"), R"(
import sys, zipfile, numpy as np, scipy.sparse as sp
f = ')" + path("ltm.npz") + R"('
with zipfile.ZipFile(f) as z:
    assert z.testzip() is None                      # every CRC-32 verified by Python
    for i in z.infolist():
        with z.open(i) as s:
            major, minor = np.lib.format.read_magic(s)
            shape, fortran, dtype = np.lib.format.read_array_header_1_0(s)
            pre = s.tell()
        print('entry', i.filename, i.compress_type, f'{major}.{minor}', dtype.str, shape, pre % 64)
T = sp.load_npz(f)
print('matrix', T.format, T.shape[0], T.shape[1], T.nnz, T.dtype, T.has_canonical_format)
print('indptr', *T.indptr.tolist())
print('indices', *T.indices.tolist())
print('data', *[float(v).hex() for v in T.data])
)",
                                            &status);
        ASSERT_EQ(status, 0) << out;
        const std::vector<std::string> expected = {
            "entry indices.npy 8 1.0 <i4 (4,) 0",
            "entry indptr.npy 8 1.0 <i4 (6,) 0",
            "entry format.npy 8 1.0 |S3 () 0",
            "entry shape.npy 8 1.0 <i8 (2,) 0",
            "entry data.npy 8 1.0 <f4 (4,) 0",
            "matrix csr 5 5 4 float32 True",
            "indptr 0 0 3 3 4 4",
            "indices 0 2 4 1",
            "data " + py_hex(m.data[0]) + " " + py_hex(m.data[1]) + " " + py_hex(m.data[2]) + " " + py_hex(m.data[3]),
        };
        EXPECT_EQ(lines_of(out), expected);
    }
}

TEST_F(LtmFileTest, ScipyAgreesOnALargeMatrix) {
    REQUIRE_SCIPY();
    // rows > 2^16; y = T x compared bit for bit: scipy's csr_matvec accumulates in the upcast type
    // (float64 for float32 data and a float64 x) in index order, as CsrMatrix::multiply does.
    const CsrMatrix m = random_matrix(70001, 1000, 8, 5);
    ltm::write_ltm_npz(path("big.npz"), m);
    int status = 0;
    const std::string out = run_python(path("big.py"), R"(
import numpy as np, scipy.sparse as sp
T = sp.load_npz(')" + path("big.npz") + R"(')
print(T.shape[0], T.shape[1], T.nnz, T.dtype)
x = ((np.arange(T.shape[1]) % 7) * 0.25 - 0.5).astype(np.float64)
for v in T @ x:
    print(float(v).hex())
)",
                                        &status);
    ASSERT_EQ(status, 0) << out.substr(0, 2000);
    const std::vector<std::string> lines = lines_of(out);
    ASSERT_EQ(lines.size(), static_cast<std::size_t>(m.rows) + 1);
    EXPECT_EQ(lines[0], "70001 1000 " + std::to_string(m.nnz()) + " float32");
    std::vector<float> x(1000);
    for (int l = 0; l < 1000; ++l) x[static_cast<std::size_t>(l)] = static_cast<float>(l % 7) * 0.25f - 0.5f;
    std::vector<double> y(static_cast<std::size_t>(m.rows));
    m.multiply(x.data(), y.data());
    int mismatches = 0;
    for (std::size_t r = 0; r < y.size(); ++r) {
        const double v = std::strtod(lines[r + 1].c_str(), nullptr);  // strtod reads C99 hex floats
        if (v != y[r] && ++mismatches <= 5) ADD_FAILURE() << "row " << r << ": scipy " << lines[r + 1] << ", ours " << y[r];
    }
    EXPECT_EQ(mismatches, 0);
}

TEST_F(LtmFileTest, ReadsFilesWrittenByScipy) {
    REQUIRE_SCIPY();
    int status = 0;
    const std::string out = run_python(path("save.py"), R"(
import numpy as np, scipy.sparse as sp
d = ')" + dir.string() + R"('
A = np.array([[0, 0.1, 0, 2.5], [0, 0, 0, 0], [-3, 0, 1e-3, 0]])
T = sp.csr_matrix(A.astype(np.float32))
sp.save_npz(d + '/c32.npz', T)                        # compressed (the default)
sp.save_npz(d + '/u32.npz', T, compressed=False)      # stored
W = sp.csr_matrix(A)                                   # float64 data
W.indices = W.indices.astype(np.int64)
W.indptr = W.indptr.astype(np.int64)
sp.save_npz(d + '/c64.npz', W)
sp.save_npz(d + '/u64.npz', W, compressed=False)
for n in ('c32', 'u32', 'c64', 'u64'):
    z = np.load(d + '/' + n + '.npz')
    print(n, z['data'].dtype.str, z['indices'].dtype.str, z['indptr'].dtype.str, z['shape'].dtype.str, z['format'].dtype.str)
print('data', *[float(v).hex() for v in T.data])
)",
                                        &status);
    ASSERT_EQ(status, 0) << out;
    const std::vector<std::string> lines = lines_of(out);
    ASSERT_EQ(lines.size(), 5u) << out;
    EXPECT_EQ(lines[0], "c32 <f4 <i4 <i4 <i8 |S3");
    EXPECT_EQ(lines[1], "u32 <f4 <i4 <i4 <i8 |S3");
    EXPECT_EQ(lines[2], "c64 <f8 <i8 <i8 <i8 |S3");
    EXPECT_EQ(lines[3], "u64 <f8 <i8 <i8 <i8 |S3");

    CsrMatrix expected;
    expected.rows = 3;
    expected.cols = 4;
    expected.indptr = {0, 2, 2, 4};
    expected.indices = {1, 3, 0, 2};
    expected.data = {static_cast<float>(0.1), 2.5f, -3.0f, static_cast<float>(1e-3)};  // float64 -> float32 rounding
    EXPECT_EQ(lines[4], "data " + py_hex(expected.data[0]) + " " + py_hex(expected.data[1]) + " " +
                            py_hex(expected.data[2]) + " " + py_hex(expected.data[3]));
    for (const char* n : {"c32", "u32", "c64", "u64"}) {
        SCOPED_TRACE(n);
        const CsrMatrix T = ltm::read_ltm_npz(path(std::string(n) + ".npz"));
        EXPECT_TRUE(same(expected, T));
    }
}

// ZIP64 as Python writes it: numpy's ZIP64 local headers on every entry, and (past 65535 entries)
// a ZIP64 end-of-central-directory record and locator. Our writer, through libzip, cannot be made
// to write these for a small file, so Python provides them.
TEST_F(LtmFileTest, ReadsZip64ArchivesWrittenByPython) {
    REQUIRE_SCIPY();
    int status = 0;
    const std::string out = run_python(path("z64.py"), R"(
import struct, zipfile, numpy as np, scipy.sparse as sp
f = ')" + path("z64.npz") + R"('
sp.save_npz(f, sp.csr_matrix(np.array([[0, 1.5, 0], [2, 0, -3]], np.float32)))
with zipfile.ZipFile(f, 'a') as z:
    for i in range(65535):
        z.writestr('pad%d' % i, b'')
raw = open(f, 'rb').read()
first_extra = struct.unpack('<H', raw[30 + len('indices.npy'):30 + len('indices.npy') + 2])[0]
print(raw[:4] == b'PK\x03\x04', first_extra == 1, b'PK\x06\x06' in raw, b'PK\x06\x07' in raw)
)",
                                        &status);
    ASSERT_EQ(status, 0) << out;
    EXPECT_EQ(out, "True True True True\n");  // a ZIP64 extra field first in the local header; ZIP64 end records
    const CsrMatrix T = ltm::read_ltm_npz(path("z64.npz"));
    CsrMatrix expected;
    expected.rows = 2;
    expected.cols = 3;
    expected.indptr = {0, 1, 3};
    expected.indices = {1, 0, 2};
    expected.data = {1.5f, 2.0f, -3.0f};
    EXPECT_TRUE(same(expected, T));
}

TEST_F(LtmFileTest, RejectsScipyFilesThatAreNotUsableCsr) {
    REQUIRE_SCIPY();
    int status = 0;
    const std::string out = run_python(path("bad.py"), R"(
import numpy as np, scipy.sparse as sp
d = ')" + dir.string() + R"('
A = np.array([[0, 1.0, 0], [2.0, 0, 3.0]], dtype=np.float32)
sp.save_npz(d + '/csc.npz', sp.csc_matrix(A))
U = sp.csr_matrix((np.array([1, 2], np.float32), np.array([2, 0], np.int32), np.array([0, 2])), shape=(1, 3))
sp.save_npz(d + '/unsorted.npz', U)
H = sp.csr_matrix((np.array([1e300, 2.0]), np.array([0, 1]), np.array([0, 2])), shape=(1, 3))
sp.save_npz(d + '/overflow.npz', H)
B = sp.csr_matrix((np.array([1.0], np.float32), np.array([3000000000], np.int64), np.array([0, 1], np.int64)), shape=(1, 2**32))
sp.save_npz(d + '/bigindex.npz', B)
I = sp.csr_matrix(np.array([[0, 7]], dtype=np.int64))
sp.save_npz(d + '/intdata.npz', I)
np.savez_compressed(d + '/plain.npz', x=np.arange(3))
f32, i32 = np.float32, np.int32
np.savez_compressed(d + '/badshape.npz', format=b'csr', shape=np.array([4, 3]), data=np.array([1.0], f32),
                    indices=np.array([0], i32), indptr=np.array([0, 1, 1], i32))
np.savez_compressed(d + '/shape3.npz', format=b'csr', shape=np.array([1, 3, 1]), data=np.array([1.0], f32),
                    indices=np.array([0], i32), indptr=np.array([0, 1], i32))
np.savez_compressed(d + '/data2d.npz', format=b'csr', shape=np.array([1, 3]), data=np.array([[1.0]], f32),
                    indices=np.array([0], i32), indptr=np.array([0, 1], i32))
np.savez(d + '/ustr.npz', format='csr', shape=np.array([1, 3]), data=np.array([1.0], f32),
         indices=np.array([2], i32), indptr=np.array([0, 1], i32))     # format as a str ('<U3')
print(np.load(d + '/ustr.npz')['format'].dtype.str)
)",
                                        &status);
    ASSERT_EQ(status, 0) << out;
    EXPECT_EQ(out, "<U3\n");
    const CsrMatrix u = ltm::read_ltm_npz(path("ustr.npz"));
    EXPECT_EQ(u.rows, 1);
    EXPECT_EQ(u.cols, 3);
    EXPECT_EQ(u.indices, std::vector<std::int32_t>{2});
    auto err = [&](const std::string& name) { return message_of([&] { ltm::read_ltm_npz(path(name)); }); };
    const std::vector<std::pair<std::string, std::string>> cases = {
        {"csc.npz", "format 'csc', not a CSR matrix"},
        {"unsorted.npz", "not strictly increasing"},
        {"overflow.npz", "overflows float32"},
        {"bigindex.npz", "column index 3000000000 of nonzero 0 in 'indices.npy' does not fit int32"},
        {"intdata.npz", "bad dtype '<i8' of array 'data.npy'"},
        {"plain.npz", "missing array 'format.npy'"},
        {"badshape.npz", "bad shape of array 'indptr.npy': 3 entries, expected rows + 1 = 5"},
        {"shape3.npz", "bad shape of array 'shape.npy'"},
        {"data2d.npz", "bad shape of array 'data.npy': it has 2 dimensions, expected 1"},
    };
    for (const auto& [name, what] : cases) {
        const std::string msg = err(name);
        EXPECT_NE(msg.find("'" + path(name) + "'"), std::string::npos) << msg;
        EXPECT_NE(msg.find(what), std::string::npos) << msg;
    }
}

// ----- corrupt files -----

TEST_F(LtmFileTest, CorruptFilesGiveErrorsNamingTheFile) {
    const CsrMatrix m = random_matrix(200, 50, 6, 11);
    ltm::write_ltm_npz(path("good.npz"), m);
    const std::string good = slurp(path("good.npz"));

    std::vector<std::pair<std::string, std::string>> cases;  // file, expected words
    spit(path("empty.npz"), "");
    cases.push_back({"empty.npz", "the file is empty"});
    spit(path("text.npz"), "this is not a zip archive at all, just some text\n");
    cases.push_back({"text.npz", "not a ZIP archive"});
    spit(path("half.npz"), good.substr(0, good.size() / 2));
    cases.push_back({"half.npz", "truncated"});
    spit(path("nodir.npz"), good.substr(0, good.size() - 10));  // end record cut
    cases.push_back({"nodir.npz", "truncated or corrupt ZIP archive"});
    {
        std::string renamed = good;  // same length, so only the names change
        for (std::size_t p = 0; (p = renamed.find("data.npy", p)) != std::string::npos;) renamed.replace(p, 8, "dat_.npy");
        spit(path("renamed.npz"), renamed);
        cases.push_back({"renamed.npz", "missing array 'data.npy'"});
    }
    {
        std::string crc = good;  // flip one bit of data.npy's CRC-32 in the central directory
        const std::size_t h = central_header_of(crc, "data.npy");
        ASSERT_NE(h, std::string::npos);
        crc[h + 16] = static_cast<char>(crc[h + 16] ^ 0x01);
        spit(path("crc.npz"), crc);
        cases.push_back({"crc.npz", "CRC-32 mismatch in entry 'data.npy'"});
    }
    {
        // Level 0: stored entries (ZIP method 0), so a flipped payload byte can only be caught by
        // the CRC.
        ltm::NpzWriteOptions o;
        o.compression_level = 0;
        ltm::write_ltm_npz(path("stored.npz"), m, o);
        std::string s = slurp(path("stored.npz"));
        const std::size_t h = central_header_of(s, "data.npy");
        ASSERT_NE(h, std::string::npos);
        const std::uint32_t off = static_cast<unsigned char>(s[h + 42]) | (static_cast<unsigned char>(s[h + 43]) << 8) |
                                  (static_cast<unsigned char>(s[h + 44]) << 16) |
                                  (static_cast<std::uint32_t>(static_cast<unsigned char>(s[h + 45])) << 24);
        const std::size_t descr = s.find("'descr': '<f4'", off);  // the .npy preamble appears verbatim
        ASSERT_NE(descr, std::string::npos);
        const std::size_t payload = s.find('\n', descr) + 1 + 40;  // a byte of the 11th value
        s[payload] = static_cast<char>(s[payload] ^ 0x40);
        spit(path("flipped.npz"), s);
        cases.push_back({"flipped.npz", "CRC-32 mismatch in entry 'data.npy'"});
    }
    {
        // a bare .npy is not an archive
        spit(path("bare.npz"), std::string("\x93NUMPY\x01\x00", 8) + "rest");
        cases.push_back({"bare.npz", "single .npy array"});
    }
    cases.push_back({"missing.npz", "no such file"});
    fs::create_directory(path("folder.npz"));
    cases.push_back({"folder.npz", "folder"});

    for (const auto& [name, what] : cases) {
        SCOPED_TRACE(name);
        const std::string msg = message_of([&] { ltm::read_ltm_npz(path(name)); });
        EXPECT_NE(msg.find("cannot read LTM file '" + path(name) + "'"), std::string::npos) << msg;
        EXPECT_NE(msg.find(what), std::string::npos) << msg;
    }
}

// ----- atomic writes -----

TEST_F(LtmFileTest, FailedWritesLeaveTheTargetUntouched) {
    const std::string target = path("ltm.npz");
    const CsrMatrix old = small_matrix();
    ltm::write_ltm_npz(target, old);
    const std::string before = slurp(target);

    // An invalid matrix is refused before anything is written.
    CsrMatrix broken = small_matrix();
    broken.indices[1] = 99;
    std::string msg = message_of([&] { ltm::write_ltm_npz(target, broken); });
    EXPECT_NE(msg.find("'" + target + "'"), std::string::npos) << msg;
    EXPECT_NE(msg.find("the matrix is invalid"), std::string::npos) << msg;

    // A write that fails half-way (file size limit): the temporary is removed, the target stays.
    {
        msg = message_under_file_size_limit([&] { ltm::write_ltm_npz(target, random_matrix(20000, 1000, 10, 1)); });
        EXPECT_NE(msg.find("cannot write LTM file '" + target + "'"), std::string::npos) << msg;
        EXPECT_NE(msg.find("File too large"), std::string::npos) << msg;
    }
    EXPECT_EQ(slurp(target), before);
    EXPECT_EQ(listing(), std::vector<std::string>{"ltm.npz"});
    EXPECT_TRUE(same(ltm::read_ltm_npz(target), old));

    // A missing folder is named.
    const std::string nowhere = path("no/such/folder/ltm.npz");
    msg = message_of([&] { ltm::write_ltm_npz(nowhere, old); });
    EXPECT_NE(msg.find("'" + nowhere + "'"), std::string::npos) << msg;
    EXPECT_NE(msg.find("the folder '" + path("no/such/folder") + "' does not exist"), std::string::npos) << msg;

    // A folder in the way of the target.
    fs::create_directory(path("taken.npz"));
    msg = message_of([&] { ltm::write_ltm_npz(path("taken.npz"), old); });
    EXPECT_NE(msg.find("'" + path("taken.npz") + "': it is a folder"), std::string::npos) << msg;
    EXPECT_EQ(listing(), (std::vector<std::string>{"ltm.npz", "taken.npz"}));
}
