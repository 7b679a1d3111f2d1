#include "orthomech/study/distributed.hpp"

#include <cmath>
#include <cstdlib>
#include <exception>
#include <stdexcept>

#ifdef ORTHOMECH_HAVE_MPI
#include <mpi.h>

#include <nlohmann/json.hpp>
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

// Every call goes through MPI's profiling names (PMPI_*): the sequential MUMPS that Ipopt brings
// (libmpiseq, linked statically) defines its own stand-ins for MPI_Init, MPI_Comm_rank and
// MPI_Finalize, which would otherwise take the place of Open MPI's and leave MPI uninitialised.
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
  PMPI_Init(nullptr, nullptr);
  PMPI_Comm_rank(MPI_COMM_WORLD, &rank_);
  PMPI_Comm_size(MPI_COMM_WORLD, &size_);
}

MpiSession::~MpiSession() {
  if (finished_)
    PMPI_Finalize();
  else
    PMPI_Abort(MPI_COMM_WORLD, 3);
}

bool broadcast_start(bool go) {
  int flag = go ? 1 : 0;
  PMPI_Bcast(&flag, 1, MPI_INT, 0, MPI_COMM_WORLD);
  return flag != 0;
}

void coordinate_variants(const std::vector<long>& pending,
                         const std::function<void(const VariantResult&)>& done) {
  int size = 1;
  PMPI_Comm_size(MPI_COMM_WORLD, &size);
  std::exception_ptr failure;
  size_t next = 0;
  int working = size - 1;
  while (working > 0) {
    MPI_Status status;
    PMPI_Probe(MPI_ANY_SOURCE, kResultTag, MPI_COMM_WORLD, &status);
    int length = 0;
    PMPI_Get_count(&status, MPI_CHAR, &length);
    std::string text(static_cast<size_t>(length), '\0');
    PMPI_Recv(text.data(), length, MPI_CHAR, status.MPI_SOURCE, kResultTag, MPI_COMM_WORLD,
              MPI_STATUS_IGNORE);
    if (!text.empty() && !failure) {
      try {
        done(unpack(text));
      } catch (...) {
        failure = std::current_exception();  // release every rank, then report
      }
    }
    long index = -1;
    if (!failure && next < pending.size()) index = pending[next++];
    if (index < 0) --working;
    PMPI_Send(&index, 1, MPI_LONG, status.MPI_SOURCE, kIndexTag, MPI_COMM_WORLD);
  }
  if (failure) std::rethrow_exception(failure);
}

void serve_variants(const std::string& mechanism, const std::string& origin, const Study& study) {
  std::string message;  // empty: ready for the first variant
  for (;;) {
    PMPI_Send(message.data(), static_cast<int>(message.size()), MPI_CHAR, 0, kResultTag,
              MPI_COMM_WORLD);
    long index = -1;
    PMPI_Recv(&index, 1, MPI_LONG, 0, kIndexTag, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
    if (index < 0) return;
    message = pack(evaluate_variant(mechanism, origin, study, index, variant_values(study, index)));
  }
}

#else  // no MPI in this build: mpi_launched() is false, so nothing below is ever called

MpiSession::MpiSession() = default;
MpiSession::~MpiSession() = default;
bool broadcast_start(bool) { throw std::logic_error("this build has no MPI"); }
void coordinate_variants(const std::vector<long>&,
                         const std::function<void(const VariantResult&)>&) {
  throw std::logic_error("this build has no MPI");
}
void serve_variants(const std::string&, const std::string&, const Study&) {
  throw std::logic_error("this build has no MPI");
}

#endif

}  // namespace orthomech
