/* carom's harness around Box2D v3 (C): the large pyramid, timed step by step on one core.
 *
 * Builds Box2D's benchmark pyramid (100 rows of unit boxes, density 1, friction 0.6, on a
 * 200 m x 2 m ground, sleep off), steps it at 60 Hz with 4 substeps for the given seconds and
 * prints one line: ms per step, how far the top box moved, and the largest rotation of any box
 * at the end. benchmarks/rigid2d.py builds and runs it when a Box2D v3 source tree is given.
 */
#define _POSIX_C_SOURCE 199309L
#include "box2d/box2d.h"
#include "box2d/math_functions.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

static double now_seconds( void )
{
	struct timespec t;
	clock_gettime( CLOCK_MONOTONIC, &t );
	return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

int main( int argc, char** argv )
{
	int rows = argc > 1 ? atoi( argv[1] ) : 100;
	double seconds = argc > 2 ? atof( argv[2] ) : 10.0;
	int steps = (int)lround( seconds * 60.0 );

	b2WorldDef worldDef = b2DefaultWorldDef();
	worldDef.enableSleep = false;
	b2WorldId world = b2CreateWorld( &worldDef );

	b2BodyDef groundDef = b2DefaultBodyDef();
	groundDef.position.x = 0.0f;
	groundDef.position.y = -1.0f;
	b2BodyId ground = b2CreateBody( world, &groundDef );
	b2ShapeDef groundShape = b2DefaultShapeDef();
	b2Polygon slab = b2MakeBox( 100.0f, 1.0f );
	b2CreatePolygonShape( ground, &groundShape, &slab );

	int count = rows * ( rows + 1 ) / 2;
	b2BodyId* boxes = malloc( sizeof( b2BodyId ) * (size_t)count );
	double* x0 = malloc( sizeof( double ) * 2 * (size_t)count );
	b2ShapeDef boxShape = b2DefaultShapeDef();
	boxShape.density = 1.0f;
	b2Polygon square = b2MakeSquare( 0.5f );
	int n = 0;
	for ( int row = 0; row < rows; ++row )
	{
		for ( int k = 0; k < rows - row; ++k )
		{
			b2BodyDef def = b2DefaultBodyDef();
			def.type = b2_dynamicBody;
			def.position.x = ( row + 1.0f ) * 0.5f + (float)k - 0.5f * (float)rows;
			def.position.y = row + 0.5f;
			boxes[n] = b2CreateBody( world, &def );
			b2CreatePolygonShape( boxes[n], &boxShape, &square );
			x0[2 * n] = def.position.x;
			x0[2 * n + 1] = def.position.y;
			++n;
		}
	}

	double wall = 0.0;
	for ( int s = 0; s < steps; ++s )
	{
		double began = now_seconds();
		b2World_Step( world, 1.0f / 60.0f, 4 );
		wall += now_seconds() - began;
	}

	int top = count - 1;
	b2Pos p = b2Body_GetPosition( boxes[top] );
	double moved = hypot( (double)p.x - x0[2 * top], (double)p.y - x0[2 * top + 1] );
	double turn = 0.0;
	for ( int i = 0; i < count; ++i )
	{
		double a = fabs( (double)b2Rot_GetAngle( b2Body_GetRotation( boxes[i] ) ) );
		turn = a > turn ? a : turn;
	}
	printf( "rows %d bodies %d steps %d ms_per_step %.4f top_moved_m %.6f max_turn_deg %.4f\n", rows,
			count, steps, 1e3 * wall / steps, moved, turn * 180.0 / 3.14159265358979 );
	b2DestroyWorld( world );
	free( boxes );
	free( x0 );
	return 0;
}
