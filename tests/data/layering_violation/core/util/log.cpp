// Test data: core/util may not include core/dataset (a later concern).
#include "core/dataset/dataset.h"
