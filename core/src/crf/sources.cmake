# The CRF: neighbourhood graph, model, inference (loopy BP, mean-field), training (L-BFGS on
# pseudo-likelihood, Bethe/BP likelihood or node-only), the SVM baseline and the metrics.
target_sources(primlabel_core PRIVATE
  ${CMAKE_CURRENT_LIST_DIR}/graph.cpp
  ${CMAKE_CURRENT_LIST_DIR}/model.cpp
  ${CMAKE_CURRENT_LIST_DIR}/potentials.cpp
  ${CMAKE_CURRENT_LIST_DIR}/belief_propagation.cpp
  ${CMAKE_CURRENT_LIST_DIR}/mean_field.cpp
  ${CMAKE_CURRENT_LIST_DIR}/inference.cpp
)
target_sources(primlabel_core PRIVATE
  ${CMAKE_CURRENT_LIST_DIR}/pseudo_likelihood.cpp
  ${CMAKE_CURRENT_LIST_DIR}/bethe_objective.cpp
  ${CMAKE_CURRENT_LIST_DIR}/training.cpp
  ${CMAKE_CURRENT_LIST_DIR}/svm_baseline.cpp
  ${CMAKE_CURRENT_LIST_DIR}/libsvm_model.cpp
  ${CMAKE_CURRENT_LIST_DIR}/metrics.cpp
)
# libsvm (libsvm-dev) for the RBF-SVM baseline.
find_library(PRIMLABEL_LIBSVM svm REQUIRED)
target_link_libraries(primlabel_core PUBLIC ${PRIMLABEL_LIBSVM})
