// The constraints of a general system given by functions (model/general_system.hpp): the
// ConstraintSystem alternative to the joints (constraint_system.hpp).
#include "orthomech/check.hpp"
#include "orthomech/constraints/constraint_system.hpp"
#include "orthomech/constraints/sparse_et.hpp"
#include "orthomech/model/general_system.hpp"

namespace orthomech {

namespace {

class GeneralConstraints final : public ConstraintSystem {
 public:
  void evaluate(const Model& model, const VecX& q, const VecX* u, VecX* f, MatX* Et, MatX* Dt,
                VecX* Dtu, const BodyPoses* /*poses*/) const override {
    if (Et) model.general->jacobian(q, *Et);
    rest(model, q, u, f, Dt, Dtu);
  }
  void evaluate(const Model& model, const VecX& q, const VecX* u, VecX* f, SparseEt* Et, MatX* Dt,
                VecX* Dtu, const BodyPoses* /*poses*/) const override {
    if (Et) Et->set_from_general(model, q);
    rest(model, q, u, f, Dt, Dtu);
  }
  // Eᵀ is a function of q: every entry may be written.
  void record_pattern(const Model& model, EtRecorder& recorder) const override {
    for (int i = 0; i < model.nc; ++i)
      for (int j = 0; j < model.n; ++j) recorder.entries.emplace_back(i, j);
  }
  bool structurally_sparse() const override { return false; }
  std::string row_name(const Model& model, int row) const override {
    check_argument(row >= 0 && row < model.nc, "constraint_row_name", "row",
                   "is out of range [0, nc)");
    return "constraint '" + model.general->rows[static_cast<size_t>(row)] + "'";
  }

 private:
  // f, Dᵀ and Dᵀu, the same for either storage of Eᵀ.
  static void rest(const Model& model, const VecX& q, const VecX* u, VecX* f, MatX* Dt, VecX* Dtu) {
    if (f) model.general->residual(q, *f);
    if (Dt) model.general->jacobian_rate(q, *u, *Dt);
    if (Dtu) {
      MatX D(model.nc, model.n);
      model.general->jacobian_rate(q, *u, D);
      *Dtu = D * *u;  // Dᵀu, the convective term of eq. (76)
    }
  }
};

const GeneralConstraints kGeneralConstraints;

}  // namespace

const ConstraintSystem& general_constraints() { return kGeneralConstraints; }

}  // namespace orthomech
