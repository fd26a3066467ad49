#pragma once
// Everything of primlabel_metrics in one include.

#include "primlabel/metrics/builder.hpp"
#include "primlabel/metrics/counter.hpp"
#include "primlabel/metrics/exposer.hpp"
#include "primlabel/metrics/exposition_parser.hpp"
#include "primlabel/metrics/family.hpp"
#include "primlabel/metrics/gauge.hpp"
#include "primlabel/metrics/histogram.hpp"
#include "primlabel/metrics/http_client.hpp"
#include "primlabel/metrics/labels.hpp"
#include "primlabel/metrics/registry.hpp"
#include "primlabel/metrics/text_format.hpp"
