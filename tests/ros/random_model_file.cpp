#include "random_model_file.hpp"

#include "primlabel/model/label_model.hpp"
#include "random_label_model.hpp"

namespace primlabel::rostest {

void write_random_label_model(const std::string& path, const std::string& name) {
  save_model(path, testing::random_label_model(name));
}

}  // namespace primlabel::rostest
