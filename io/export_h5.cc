// The HDF5 model export of io/export.cc (layout in docs/export.md); in the
// plugin zwidth-hdf5.so for the zwidth executable (io/hdf5_api.h).
#include <optional>
#include <string>
#include <vector>

#include <H5Cpp.h>

#include "model/units.h"
#include "io/hdf5_api.h"
#include "io/io_internal.h"
#include "model/error.h"
#include "model/state_space.h"

namespace zwidth::io::internal {

void WriteModelHdf5(const std::string& tmp, const ModelFile& mf, double T) {
  H5::Exception::dontPrint();
  try {
    H5::H5File f(tmp, H5F_ACC_TRUNC);
    auto units = [](H5::H5Object& o, const std::string& u) {
      H5::StrType st(H5::PredType::C_S1, u.size());
      o.createAttribute("units", st, H5::DataSpace(H5S_SCALAR)).write(st, u);
    };
    auto vec = [&](H5::Group& g, const std::string& name, const std::vector<double>& v, const std::string& u) {
      const hsize_t n = v.size();
      H5::DataSpace sp(1, &n);
      H5::DataSet ds = g.createDataSet(name, H5::PredType::IEEE_F64LE, sp);
      if (n) ds.write(v.data(), H5::PredType::NATIVE_DOUBLE);
      units(ds, u);
    };
    auto int_attr = [](H5::H5Object& o, const char* name, int v) {
      o.createAttribute(name, H5::PredType::STD_I32LE, H5::DataSpace(H5S_SCALAR)).write(H5::PredType::NATIVE_INT, &v);
    };
    auto mat = [&](H5::Group& g, const std::string& name, const Eigen::MatrixXd& M) {
      const hsize_t dims[2] = {static_cast<hsize_t>(M.rows()), static_cast<hsize_t>(M.cols())};
      H5::DataSpace sp(2, dims);
      H5::DataSet ds = g.createDataSet(name, H5::PredType::IEEE_F64LE, sp);
      const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> R = M;
      ds.write(R.data(), H5::PredType::NATIVE_DOUBLE);
    };
    auto params = [&](const std::string& gname, const model::Plant& p, const std::optional<model::Friction>& fr) {
      H5::Group g = f.createGroup(gname);
      if (fr) for (const auto& [name, v] : FrictionFields(*fr)) vec(g, "friction_" + name, {v}, "input units");
      vec(g, "m", {p.m}, model::Units(mf.linear).m);
      vec(g, "b", {p.b}, model::Units(mf.linear).b);
      std::vector<double> w, c, v, d;
      for (const model::Mode& md : p.modes) { w.push_back(md.omega); c.push_back(md.c); v.push_back(md.v); d.push_back(md.d); }
      vec(g, "omega", w, "rad/s"); vec(g, "c", c, "rad/s"); vec(g, "v", v, "rad/s"); vec(g, "d", d, "rad/s");
    };
    params("/parameters", mf.plant, mf.friction);
    if (mf.std_errors) params("/std", *mf.std_errors, mf.friction_std);
    const model::StateSpace c = model::ContinuousStateSpace(mf.plant);
    H5::Group gc = f.createGroup("/continuous");
    mat(gc, "A", c.A); mat(gc, "B", c.B); mat(gc, "C", c.C); mat(gc, "D", Eigen::MatrixXd::Constant(1, 1, c.D));
    H5::Group root = f.openGroup("/");
    int_attr(root, "delay_samples", mf.plant.delay_samples);
    if (T > 0) {
      const model::StateSpace d = model::WithDelayStates(model::DiscretizeZoh(mf.plant, T));
      H5::Group gd = f.createGroup("/discrete");
      mat(gd, "A", d.A); mat(gd, "B", d.B); mat(gd, "C", d.C); mat(gd, "D", Eigen::MatrixXd::Constant(1, 1, d.D));
      internal::WriteDoubleAttr(gd, "period_s", T);
      int_attr(gd, "delay_samples_realised_as_states", mf.plant.delay_samples);
    }
  } catch (const H5::Exception& e) {
    throw InputError("cannot write HDF5 '" + tmp + "': " + e.getDetailMsg());
  }
}


}  // namespace zwidth::io::internal
