#include "orthomech/study/distributed.hpp"

#include <cmath>
#include <cstdlib>
#include <exception>
#include <stdexcept>
#include <vector>

#ifdef ORTHOMECH_HAVE_MPI
#define OMPI_SKIP_MPICXX 1  // the C API only: no libmpi_cxx
#include <mpi.h>

#include <nlohmann/json.hpp>

#include "../io/shared_library.hpp"
#ifndef OPEN_MPI
#error "distributed.cpp opens Open MPI's libmpi.so.40 at run time (its handles are its globals)"
#endif
#endif

namespace orthomech {

bool mpi_launched() {
#ifdef ORTHOMECH_HAVE_MPI
  for (const char* variable : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_SIZE"})
    if (const char* v = std::getenv(variable)) return std::atoi(v) > 1;
#endif
  return false;
}

#ifdef ORTHOMECH_HAVE_MPI

namespace {

// Open MPI, opened when a process started by mpirun first needs it (io/shared_library.hpp): the
// other commands, and sweep on one process, do not load it and the 6 libraries it brings. Its
// symbols resolve the components it opens itself (RTLD_GLOBAL). Every call goes through MPI's
// profiling names (PMPI_*), Open MPI's own whatever else the process defines: the sequential
// MUMPS that Ipopt brings (libmpiseq, linked statically) has stand-ins for MPI_Init,
// MPI_Comm_rank and MPI_Finalize. Open MPI's handles (MPI_COMM_WORLD, MPI_INT, …) are the
// addresses of its global objects, looked up by name like the functions.
struct MpiApi {
  explicit MpiApi(const detail::SharedLibrary& lib)
      : init(lib.function<decltype(::PMPI_Init)>("PMPI_Init")),
        comm_rank(lib.function<decltype(::PMPI_Comm_rank)>("PMPI_Comm_rank")),
        comm_size(lib.function<decltype(::PMPI_Comm_size)>("PMPI_Comm_size")),
        finalize(lib.function<decltype(::PMPI_Finalize)>("PMPI_Finalize")),
        abort(lib.function<decltype(::PMPI_Abort)>("PMPI_Abort")),
        bcast(lib.function<decltype(::PMPI_Bcast)>("PMPI_Bcast")),
        probe(lib.function<decltype(::PMPI_Probe)>("PMPI_Probe")),
        get_count(lib.function<decltype(::PMPI_Get_count)>("PMPI_Get_count")),
        recv(lib.function<decltype(::PMPI_Recv)>("PMPI_Recv")),
        send(lib.function<decltype(::PMPI_Send)>("PMPI_Send")),
        allgatherv(lib.function<decltype(::PMPI_Allgatherv)>("PMPI_Allgatherv")),
        world(static_cast<MPI_Comm>(lib.symbol("ompi_mpi_comm_world"))),
        int_type(static_cast<MPI_Datatype>(lib.symbol("ompi_mpi_int"))),
        char_type(static_cast<MPI_Datatype>(lib.symbol("ompi_mpi_char"))),
        long_type(static_cast<MPI_Datatype>(lib.symbol("ompi_mpi_long"))),
        double_type(static_cast<MPI_Datatype>(lib.symbol("ompi_mpi_double"))) {}
  decltype(&::PMPI_Init) init;
  decltype(&::PMPI_Comm_rank) comm_rank;
  decltype(&::PMPI_Comm_size) comm_size;
  decltype(&::PMPI_Finalize) finalize;
  decltype(&::PMPI_Abort) abort;
  decltype(&::PMPI_Bcast) bcast;
  decltype(&::PMPI_Probe) probe;
  decltype(&::PMPI_Get_count) get_count;
  decltype(&::PMPI_Recv) recv;
  decltype(&::PMPI_Send) send;
  decltype(&::PMPI_Allgatherv) allgatherv;
  MPI_Comm world;
  MPI_Datatype int_type, char_type, long_type, double_type;
};

const MpiApi& mpi() {
  static const detail::SharedLibrary lib({"libmpi.so.40"}, true, "libopenmpi3");
  static const MpiApi api(lib);
  return api;
}
constexpr int kResultTag = 1;  // worker → rank 0: a result (or an empty "ready")
constexpr int kIndexTag = 2;   // rank 0 → worker: the next variant, −1 when there is none

std::string pack(const VariantResult& r) {
  nlohmann::json j = {{"index", r.index},
                      {"values", r.values},
                      {"status", r.status},
                      {"message", r.message},
                      {"positions", r.positions}};
  nlohmann::json metrics = nlohmann::json::array();
  for (const auto& [name, value] : r.metrics)  // NaN is not JSON: null
    metrics.push_back({name, std::isnan(value) ? nlohmann::json() : nlohmann::json(value)});
  j["metrics"] = metrics;
  return j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

VariantResult unpack(const std::string& text) {
  const nlohmann::json j = nlohmann::json::parse(text);
  VariantResult r;
  r.index = j["index"].get<long>();
  r.values = j["values"].get<std::vector<double>>();
  r.status = j["status"].get<std::string>();
  r.message = j["message"].get<std::string>();
  r.positions = j["positions"].get<long>();
  for (const auto& m : j["metrics"])
    r.metrics.emplace_back(m[0].get<std::string>(),
                           m[1].is_null() ? std::nan("") : m[1].get<double>());
  return r;
}

}  // namespace

MpiSession::MpiSession() {
  mpi().init(nullptr, nullptr);
  mpi().comm_rank(mpi().world, &rank_);
  mpi().comm_size(mpi().world, &size_);
}

MpiSession::~MpiSession() {
  if (finished_)
    mpi().finalize();
  else
    mpi().abort(mpi().world, 3);
}

ProcessShare mpi_share(const MpiSession& session) {
  ProcessShare share;
  share.rank = session.rank();
  share.size = session.size();
  share.gather = [](const std::vector<double>& mine, const std::vector<int>& counts) {
    std::vector<int> offsets(counts.size(), 0);
    for (size_t r = 1; r < counts.size(); ++r) offsets[r] = offsets[r - 1] + counts[r - 1];
    std::vector<double> all(static_cast<size_t>(offsets.back() + counts.back()));
    mpi().allgatherv(mine.data(), static_cast<int>(mine.size()), mpi().double_type, all.data(),
                     counts.data(), offsets.data(), mpi().double_type, mpi().world);
    return all;
  };
  return share;
}

bool broadcast_start(bool go) {
  int flag = go ? 1 : 0;
  mpi().bcast(&flag, 1, mpi().int_type, 0, mpi().world);
  return flag != 0;
}

void coordinate_variants(const std::function<long()>& next,
                         const std::function<void(const VariantResult&)>& done) {
  int size = 1;
  mpi().comm_size(mpi().world, &size);
  std::exception_ptr failure;
  int working = size - 1;
  while (working > 0) {
    MPI_Status status;
    mpi().probe(MPI_ANY_SOURCE, kResultTag, mpi().world, &status);
    int length = 0;
    mpi().get_count(&status, mpi().char_type, &length);
    std::string text(static_cast<size_t>(length), '\0');
    mpi().recv(text.data(), length, mpi().char_type, status.MPI_SOURCE, kResultTag, mpi().world,
               MPI_STATUS_IGNORE);
    if (!text.empty() && !failure) {
      try {
        done(unpack(text));
      } catch (...) {
        failure = std::current_exception();  // release every rank, then report
      }
    }
    long index = -1;
    if (!failure) index = next();
    if (index < 0) --working;
    mpi().send(&index, 1, mpi().long_type, status.MPI_SOURCE, kIndexTag, mpi().world);
  }
  if (failure) std::rethrow_exception(failure);
}

void serve_variants(const std::string& mechanism, const std::string& origin, const Study& study) {
  std::string message;  // empty: ready for the first variant
  for (;;) {
    mpi().send(message.data(), static_cast<int>(message.size()), mpi().char_type, 0, kResultTag,
               mpi().world);
    long index = -1;
    mpi().recv(&index, 1, mpi().long_type, 0, kIndexTag, mpi().world, MPI_STATUS_IGNORE);
    if (index < 0) return;
    message = pack(evaluate_variant(mechanism, origin, study, index, variant_values(study, index)));
  }
}

#else  // no MPI in this build: mpi_launched() is false, so nothing below is ever called

MpiSession::MpiSession() = default;
MpiSession::~MpiSession() = default;
ProcessShare mpi_share(const MpiSession&) { throw std::logic_error("this build has no MPI"); }
bool broadcast_start(bool) { throw std::logic_error("this build has no MPI"); }
void coordinate_variants(const std::function<long()>&,
                         const std::function<void(const VariantResult&)>&) {
  throw std::logic_error("this build has no MPI");
}
void serve_variants(const std::string&, const std::string&, const Study&) {
  throw std::logic_error("this build has no MPI");
}

#endif

}  // namespace orthomech
