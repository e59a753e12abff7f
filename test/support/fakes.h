// Test doubles for the core's seams (the frame helpers are in frames.h).
#ifndef HUBWIRE_TEST_FAKES_H
#define HUBWIRE_TEST_FAKES_H

#include "frames.h"
#include "port_fake.h"
#include "hubwire/port.h"

#endif
