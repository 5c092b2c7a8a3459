// Test data: datagen may not include method/.
#include "method/x.h"
